// ORB-SLAM2's binary vocabulary (ORBvoc.bin, from ORB-SLAM2 pull request 21,
// kept by many forks: loadFromBinaryFile / saveToBinaryFile), little-endian:
//   u32 node_count (with the root), u32 record_size (= 4 + code_size + 4 + 1),
//   i32 k, i32 L, i32 scoring, i32 weighting,
//   then for nodes 1 .. node_count - 1:
//     i32 parent, code_size descriptor bytes, f32 weight, u8 is_leaf.
// Word ids number the leaves in node order.
#include <cmath>

#include "binbow/error.h"
#include "core/little_endian.h"
#include "formats/byte_reader.h"
#include "formats/codecs.h"
#include "formats/tree_checks.h"

namespace binbow::detail {

namespace {
constexpr std::size_t kHeaderSize = 24;
constexpr std::size_t kRecordOverhead = 9;  // parent, weight, leaf flag
}  // namespace

ParsedVocabulary parse_orbslam_binary(const std::uint8_t* data, std::size_t size,
                                      const std::string& name) {
  ByteReader in(data, size, name);
  const std::uint32_t node_count = in.read<std::uint32_t>("the header");
  const std::uint32_t record_size = in.read<std::uint32_t>("the header");
  const std::int32_t branching = in.read<std::int32_t>("the header");
  const std::int32_t levels = in.read<std::int32_t>("the header");
  const std::int32_t scoring = in.read<std::int32_t>("the header");
  const std::int32_t weighting = in.read<std::int32_t>("the header");
  if (node_count < 2) in.fail("header: " + std::to_string(node_count) + " nodes, need at least 2");
  if (record_size <= kRecordOverhead || record_size - kRecordOverhead > kMaxCodeSize)
    in.fail("header: node record size " + std::to_string(record_size) + " is outside " +
            std::to_string(kRecordOverhead + 1) + ".." +
            std::to_string(kRecordOverhead + kMaxCodeSize));
  check_header_values(name, "header", branching, levels, scoring, weighting);
  const std::uint64_t expected = std::uint64_t{node_count - 1} * record_size;
  if (expected != in.remaining())
    in.fail("the header announces " + std::to_string(node_count - 1) + " node records of " +
            std::to_string(record_size) + " bytes (" + std::to_string(expected) +
            " bytes) but the file has " + std::to_string(in.remaining()) + " after the header" +
            (expected > in.remaining() ? " (truncated)" : ""));

  ParsedVocabulary parsed;
  VocabularyTree& tree = parsed.tree;
  const std::size_t code_size = record_size - kRecordOverhead;
  tree.code_size = code_size;
  tree.branching = static_cast<std::uint32_t>(branching);
  tree.levels = static_cast<std::uint32_t>(levels);
  tree.scoring = scoring_from_code(scoring);
  tree.weighting = weighting_from_code(weighting);
  tree.parent.assign(node_count, 0);
  tree.descriptors.assign(std::size_t{node_count} * code_size, 0);
  tree.weights.assign(node_count, 0.0f);
  std::vector<std::uint8_t> leaf_flags(node_count, 0);
  for (std::size_t node = 1; node < node_count; ++node) {
    const std::uint8_t* record = in.take(record_size, "a node record");
    const std::int32_t parent = load_le<std::int32_t>(record);
    const float weight = load_le<float>(record + 4 + code_size);
    const std::uint8_t leaf = record[8 + code_size];
    if (parent < 0)
      in.fail("node record " + std::to_string(node) + ": negative parent id " +
              std::to_string(parent));
    if (!std::isfinite(weight))
      in.fail("node record " + std::to_string(node) + ": weight is not finite");
    if (leaf > 1)
      in.fail("node record " + std::to_string(node) + ": leaf flag " + std::to_string(leaf) +
              " is not 0 or 1");
    tree.parent[node] = static_cast<NodeId>(parent);
    std::memcpy(tree.descriptors.data() + node * code_size, record + 4, code_size);
    tree.weights[node] = weight;
    leaf_flags[node] = leaf;
  }
  check_listed_tree(tree, leaf_flags, name, "node record", 0);
  return parsed;
}

std::vector<std::uint8_t> format_orbslam_binary(const VocabularyTree& tree) {
  const ChildLists children = child_lists(tree);
  const std::size_t nodes = tree.node_count();
  const std::size_t record_size = tree.code_size + kRecordOverhead;
  std::vector<std::uint8_t> out;
  out.reserve(kHeaderSize + (nodes - 1) * record_size);
  put_le(out, static_cast<std::uint32_t>(nodes));
  put_le(out, static_cast<std::uint32_t>(record_size));
  put_le(out, static_cast<std::int32_t>(tree.branching));
  put_le(out, static_cast<std::int32_t>(tree.levels));
  put_le(out, static_cast<std::int32_t>(tree.scoring));
  put_le(out, static_cast<std::int32_t>(tree.weighting));
  for (std::size_t node = 1; node < nodes; ++node) {
    const bool leaf = children.first[node] == children.first[node + 1];
    put_le(out, static_cast<std::int32_t>(tree.parent[node]));
    const std::uint8_t* descriptor = tree.descriptors.data() + node * tree.code_size;
    out.insert(out.end(), descriptor, descriptor + tree.code_size);
    put_le(out, leaf ? tree.weights[node] : 0.0f);
    out.push_back(leaf ? 1 : 0);
  }
  return out;
}

}  // namespace binbow::detail
