// DBoW3's binary vocabulary (.dbow3, Vocabulary::toStream), little-endian:
//   u64 signature 88877711233, u8 compressed, u32 node_count (with the root);
//   then, QuickLZ-compressed in 10000-byte chunks when `compressed` is set:
//   i32 k, i32 L, i32 scoring, i32 weighting;
//   node_count - 1 records: u32 id, u32 parent, f64 weight,
//     i32 cols, i32 rows, i32 OpenCV type, cols × element-size descriptor bytes;
//   u32 word_count, word_count × (u32 word id, u32 node id).
// Records come parent by parent (DBoW3's traversal order), ids are explicit.
// QuickLZ has no Debian package, so compressed files are refused with advice.
#include <cmath>

#include "binbow/error.h"
#include "core/little_endian.h"
#include "formats/byte_reader.h"
#include "formats/codecs.h"
#include "formats/tree_checks.h"

namespace binbow::detail {

namespace {
constexpr std::uint64_t kSignature = 88877711233ull;
constexpr std::size_t kRecordHeader = 4 + 4 + 8 + 12;
constexpr std::int32_t kOpenCvType8U = 0;
}  // namespace

ParsedVocabulary parse_dbow3_binary(const std::uint8_t* data, std::size_t size,
                                    const std::string& name) {
  ByteReader in(data, size, name);
  if (in.read<std::uint64_t>("the signature") != kSignature)
    in.fail("not a DBoW3 binary vocabulary: wrong signature");
  const std::uint8_t compressed = in.read<std::uint8_t>("the header");
  const std::uint32_t node_count = in.read<std::uint32_t>("the header");
  if (compressed != 0)
    in.fail(
        "unsupported: compressed DBoW3 (QuickLZ), re-save uncompressed "
        "(DBoW3: vocabulary.save(file, false)) or as YAML");
  if (node_count < 2) in.fail("header: " + std::to_string(node_count) + " nodes, need at least 2");
  const std::int32_t branching = in.read<std::int32_t>("the header");
  const std::int32_t levels = in.read<std::int32_t>("the header");
  const std::int32_t scoring = in.read<std::int32_t>("the header");
  const std::int32_t weighting = in.read<std::int32_t>("the header");
  check_header_values(name, "header", branching, levels, scoring, weighting);
  if (std::uint64_t{node_count - 1} * (kRecordHeader + 1) > in.remaining())
    in.fail("truncated: the header announces " + std::to_string(node_count - 1) +
            " node records, more than the file can hold");

  ParsedVocabulary parsed;
  VocabularyTree& tree = parsed.tree;
  tree.branching = static_cast<std::uint32_t>(branching);
  tree.levels = static_cast<std::uint32_t>(levels);
  tree.scoring = scoring_from_code(scoring);
  tree.weighting = weighting_from_code(weighting);
  constexpr NodeId kUnset = UINT32_MAX;
  tree.parent.assign(node_count, kUnset);
  tree.parent[0] = 0;
  tree.weights.assign(node_count, 0.0f);
  std::size_t code_size = 0;
  for (std::size_t record = 1; record < node_count; ++record) {
    const std::uint8_t* header = in.take(kRecordHeader, "a node record");
    const std::uint32_t id = load_le<std::uint32_t>(header);
    const std::uint32_t parent = load_le<std::uint32_t>(header + 4);
    const double weight = load_le<double>(header + 8);
    const std::int32_t cols = load_le<std::int32_t>(header + 16);
    const std::int32_t rows = load_le<std::int32_t>(header + 20);
    const std::int32_t type = load_le<std::int32_t>(header + 24);
    const std::string where =
        "node record " + std::to_string(record) + " (id " + std::to_string(id) + "): ";
    if (type != kOpenCvType8U || rows != 1)
      in.fail(where + "descriptor of OpenCV type " + std::to_string(type) + " with " +
              std::to_string(rows) +
              " rows; only binary descriptors (CV_8U, one row) are supported");
    if (cols < 1 || static_cast<std::size_t>(cols) > kMaxCodeSize)
      in.fail(where + "descriptor of " + std::to_string(cols) + " bytes");
    if (code_size == 0) {
      code_size = static_cast<std::size_t>(cols);
      tree.code_size = code_size;
      if (std::uint64_t{node_count - 1} * (kRecordHeader + code_size) >
          in.remaining() + kRecordHeader)
        in.fail("truncated: " + std::to_string(node_count - 1) + " node records of " +
                std::to_string(kRecordHeader + code_size) + " bytes do not fit in the file");
      tree.descriptors.assign(std::size_t{node_count} * code_size, 0);
    } else if (static_cast<std::size_t>(cols) != code_size) {
      in.fail(where + "descriptor of " + std::to_string(cols) + " bytes where the first had " +
              std::to_string(code_size));
    }
    const std::uint8_t* descriptor = in.take(code_size, "a node descriptor");
    if (id == 0 || id >= node_count)
      in.fail(where + "node id is outside 1.." + std::to_string(node_count - 1));
    if (tree.parent[id] != kUnset) in.fail(where + "node id appears twice");
    if (parent >= node_count || parent == id)
      in.fail(where + "parent id " + std::to_string(parent) + " is not another node of the tree");
    if (!std::isfinite(weight) || std::fabs(weight) > 3.4e38)
      in.fail(where + "weight is not a finite float");
    tree.parent[id] = parent;
    tree.weights[id] = static_cast<float>(weight);
    std::memcpy(tree.descriptors.data() + std::size_t{id} * code_size, descriptor, code_size);
  }
  const std::uint32_t word_count = in.read<std::uint32_t>("the word count");
  if (std::uint64_t{word_count} * 8 != in.remaining())
    in.fail("the word list announces " + std::to_string(word_count) + " words (" +
            std::to_string(std::uint64_t{word_count} * 8) + " bytes) but " +
            std::to_string(in.remaining()) + " bytes remain");
  std::vector<std::pair<std::uint32_t, std::uint32_t>> words(word_count);
  for (auto& [word, node] : words) {
    word = in.read<std::uint32_t>("a word");
    node = in.read<std::uint32_t>("a word");
  }
  parsed.word_ids_match = check_word_list(tree, words, name);
  return parsed;
}

std::vector<std::uint8_t> format_dbow3_binary(const VocabularyTree& tree) {
  const ChildLists children = child_lists(tree);
  const std::size_t nodes = tree.node_count();
  std::vector<std::uint8_t> out;
  out.reserve(32 + nodes * (kRecordHeader + tree.code_size + 8));
  put_le(out, kSignature);
  out.push_back(0);  // not compressed
  put_le(out, static_cast<std::uint32_t>(nodes));
  put_le(out, static_cast<std::int32_t>(tree.branching));
  put_le(out, static_cast<std::int32_t>(tree.levels));
  put_le(out, static_cast<std::int32_t>(tree.scoring));
  put_le(out, static_cast<std::int32_t>(tree.weighting));
  std::vector<NodeId> parents{0};  // DBoW3's order: next parent from the back of a stack
  while (!parents.empty()) {
    const NodeId parent = parents.back();
    parents.pop_back();
    for (std::uint32_t c = children.first[parent]; c < children.first[parent + 1]; ++c) {
      const NodeId node = children.child[c];
      const bool leaf = children.first[node] == children.first[node + 1];
      put_le(out, static_cast<std::uint32_t>(node));
      put_le(out, static_cast<std::uint32_t>(parent));
      put_le(out, leaf ? static_cast<double>(tree.weights[node]) : 0.0);
      put_le(out, static_cast<std::int32_t>(tree.code_size));
      put_le(out, std::int32_t{1});
      put_le(out, kOpenCvType8U);
      const std::uint8_t* descriptor = tree.descriptors.data() + node * tree.code_size;
      out.insert(out.end(), descriptor, descriptor + tree.code_size);
      if (!leaf) parents.push_back(node);
    }
  }
  std::uint32_t words = 0;
  for (std::size_t node = 1; node < nodes; ++node)
    if (children.first[node] == children.first[node + 1]) ++words;
  put_le(out, words);
  std::uint32_t word = 0;
  for (std::size_t node = 1; node < nodes; ++node) {
    if (children.first[node] != children.first[node + 1]) continue;
    put_le(out, word++);
    put_le(out, static_cast<std::uint32_t>(node));
  }
  return out;
}

}  // namespace binbow::detail
