// The binary vocabulary of VINS-Mono and VINS-Fusion (brief_k10L6.bin, their
// VINSLoop::Vocabulary: loadBin / saveBin), little-endian, no magic:
//   i32 k, i32 L, i32 scoring, i32 weighting, i32 node_count (without the
//   root), i32 word_count;
//   node_count × 48-byte records: i32 id, i32 parent id, f64 weight,
//     u64 descriptor[4] (BRIEF test i is bit i % 64 of descriptor[i / 64]);
//   word_count × (i32 node id, i32 word id).
// The file is exactly 24 + 48·node_count + 8·word_count bytes; detection
// relies on it. The root (id 0) is not stored. VINS gives each node its
// children in file order, binbow in id order: the two agree because VINS
// writes records in id order, and files listing siblings otherwise are
// refused rather than read with another tie order.
#include <cmath>
#include <cstring>
#include <limits>

#include "binbow/error.h"
#include "core/little_endian.h"
#include "formats/byte_reader.h"
#include "formats/codecs.h"
#include "formats/tree_checks.h"

namespace binbow::detail {

namespace {
constexpr std::size_t kHeaderSize = 24;
constexpr std::size_t kRecordSize = 16 + kVinsCodeSize;
constexpr std::size_t kWordSize = 8;
}  // namespace

std::uint64_t vins_binary_size(std::int64_t node_count, std::int64_t word_count) {
  return kHeaderSize + kRecordSize * static_cast<std::uint64_t>(node_count) +
         kWordSize * static_cast<std::uint64_t>(word_count);
}

ParsedVocabulary parse_vins_binary(const std::uint8_t* data, std::size_t size,
                                   const std::string& name) {
  ByteReader in(data, size, name);
  const std::int32_t branching = in.read<std::int32_t>("the header");
  const std::int32_t levels = in.read<std::int32_t>("the header");
  const std::int32_t scoring = in.read<std::int32_t>("the header");
  const std::int32_t weighting = in.read<std::int32_t>("the header");
  const std::int32_t node_records = in.read<std::int32_t>("the header");
  const std::int32_t word_count = in.read<std::int32_t>("the header");
  if (node_records < 1)
    in.fail("header: " + std::to_string(node_records) + " nodes, need at least 1");
  if (word_count < 1) in.fail("header: " + std::to_string(word_count) + " words, need at least 1");
  const std::uint64_t expected = vins_binary_size(node_records, word_count);
  if (expected != size)
    in.fail("the header announces " + std::to_string(node_records) + " nodes and " +
            std::to_string(word_count) + " words (" + std::to_string(expected) +
            " bytes) but the file has " + std::to_string(size) + " bytes" +
            (expected > size ? " (truncated)" : ""));
  check_header_values(name, "header", branching, levels, scoring, weighting);

  ParsedVocabulary parsed;
  VocabularyTree& tree = parsed.tree;
  const std::size_t node_count = std::size_t{static_cast<std::uint32_t>(node_records)} + 1;
  tree.code_size = kVinsCodeSize;
  tree.branching = static_cast<std::uint32_t>(branching);
  tree.levels = static_cast<std::uint32_t>(levels);
  tree.scoring = scoring_from_code(scoring);
  tree.weighting = weighting_from_code(weighting);
  constexpr NodeId kUnset = std::numeric_limits<NodeId>::max();
  tree.parent.assign(node_count, kUnset);
  tree.parent[0] = 0;
  tree.descriptors.assign(node_count * kVinsCodeSize, 0);
  tree.weights.assign(node_count, 0.0f);
  std::vector<NodeId> last_child(node_count, 0);
  for (std::size_t record = 1; record < node_count; ++record) {
    const std::uint8_t* bytes = in.take(kRecordSize, "a node record");
    const std::int32_t id = load_le<std::int32_t>(bytes);
    const std::int32_t parent = load_le<std::int32_t>(bytes + 4);
    const double weight = load_le<double>(bytes + 8);
    const std::string where =
        "node record " + std::to_string(record) + " (id " + std::to_string(id) + "): ";
    if (id < 1 || id > node_records)
      in.fail(where + "node id is outside 1.." + std::to_string(node_records));
    if (tree.parent[id] != kUnset) in.fail(where + "node id appears twice");
    if (parent < 0 || parent > node_records || parent == id)
      in.fail(where + "parent id " + std::to_string(parent) + " is not another node of the tree");
    if (static_cast<NodeId>(id) < last_child[parent])
      in.fail(where + "listed after its sibling " + std::to_string(last_child[parent]) +
              "; VINS orders siblings as listed, binbow by id, so the two would disagree");
    if (!std::isfinite(weight) || std::fabs(weight) > std::numeric_limits<float>::max())
      in.fail(where + "weight is not a finite float");
    last_child[parent] = static_cast<NodeId>(id);
    tree.parent[id] = static_cast<NodeId>(parent);
    tree.weights[id] = static_cast<float>(weight);
    std::memcpy(
        tree.descriptors.data() + std::size_t{static_cast<std::uint32_t>(id)} * kVinsCodeSize,
        bytes + 16, kVinsCodeSize);
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> words;
  words.reserve(static_cast<std::uint32_t>(word_count));
  for (std::int32_t w = 0; w < word_count; ++w) {
    const std::int32_t node = in.read<std::int32_t>("a word record");
    const std::int32_t word = in.read<std::int32_t>("a word record");
    if (node < 1 || node > node_records || word < 0)
      in.fail("word record " + std::to_string(w) + ": node id " + std::to_string(node) +
              " or word id " + std::to_string(word) + " is outside the tree");
    words.emplace_back(static_cast<std::uint32_t>(word), static_cast<std::uint32_t>(node));
  }
  parsed.word_ids_match = check_word_list(tree, words, name);
  return parsed;
}

std::vector<std::uint8_t> format_vins_binary(const VocabularyTree& tree) {
  if (tree.code_size != kVinsCodeSize)
    throw InvalidArgument("the VINS format holds 256-bit descriptors only; this vocabulary has " +
                          std::to_string(tree.code_size * 8) + "-bit ones");
  const std::size_t nodes = tree.node_count();
  if (nodes - 1 > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw InvalidArgument("the VINS format holds at most 2^31 - 1 nodes");
  const ChildLists children = child_lists(tree);
  const auto is_leaf = [&](std::size_t node) {
    return children.first[node] == children.first[node + 1];
  };
  std::int32_t words = 0;
  for (std::size_t node = 1; node < nodes; ++node)
    if (is_leaf(node)) ++words;
  std::vector<std::uint8_t> out;
  out.reserve(vins_binary_size(static_cast<std::int64_t>(nodes - 1), words));
  put_le(out, static_cast<std::int32_t>(tree.branching));
  put_le(out, static_cast<std::int32_t>(tree.levels));
  put_le(out, static_cast<std::int32_t>(tree.scoring));
  put_le(out, static_cast<std::int32_t>(tree.weighting));
  put_le(out, static_cast<std::int32_t>(nodes - 1));
  put_le(out, words);
  for (std::size_t node = 1; node < nodes; ++node) {
    put_le(out, static_cast<std::int32_t>(node));
    put_le(out, static_cast<std::int32_t>(tree.parent[node]));
    put_le(out, is_leaf(node) ? static_cast<double>(tree.weights[node]) : 0.0);
    // binbow keeps BRIEF test i at bit i % 8 of byte i / 8: as little-endian
    // 64-bit words that is bit i % 64 of word i / 64, VINS's layout.
    const std::uint8_t* descriptor = tree.descriptors.data() + node * kVinsCodeSize;
    out.insert(out.end(), descriptor, descriptor + kVinsCodeSize);
  }
  std::int32_t word = 0;
  for (std::size_t node = 1; node < nodes; ++node) {
    if (!is_leaf(node)) continue;
    put_le(out, static_cast<std::int32_t>(node));
    put_le(out, word++);
  }
  return out;
}

}  // namespace binbow::detail
