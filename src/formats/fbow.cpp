// fbow's vocabulary (.fbow, fbow::Vocabulary::toStream), little-endian:
//   u64 signature 55824124;
//   the `params` struct, 120 bytes: char desc_name[50], (2 bytes padding),
//     u32 alignment, u32 block_count, u64 descriptor_stride, u64 block_size,
//     u64 feature_offset, u64 child_offset, u64 total_size,
//     i32 OpenCV descriptor type, i32 descriptor bytes, u32 k, (4 bytes padding);
//   total_size bytes: block_count blocks of block_size bytes. A block holds
//   the children of one inner node (block 0: the root's):
//     u16 child count N, u16 all-leaves flag, u32 parent node id,
//     at feature_offset: k descriptors, descriptor_stride bytes apart,
//     at child_offset: k × (u32 link, f32 weight), where a link with the
//     high bit set is a leaf whose low 31 bits are its word id, and
//     otherwise the block of the child's own children.
// fbow stores neither L nor the weighting and scoring types: L is read as
// the tree's depth, weighting and scoring as tf-idf and L1 (fbow's use).
#include <algorithm>
#include <cmath>
#include <cstring>

#include "binbow/error.h"
#include "core/little_endian.h"
#include "formats/byte_reader.h"
#include "formats/codecs.h"
#include "formats/tree_checks.h"

namespace binbow::detail {

namespace {

constexpr std::uint64_t kSignature = 55824124ull;
constexpr std::size_t kParamsSize = 120;
constexpr std::uint32_t kLeafBit = 0x80000000u;
constexpr std::uint32_t kWriteAlignment = 8;  // fbow's choice for binary descriptors

std::uint64_t round_up(std::uint64_t value, std::uint64_t alignment) {
  return (value + alignment - 1) / alignment * alignment;
}

struct Layout {
  std::uint64_t stride = 0, feature_offset = 0, child_offset = 0, block_size = 0;
};

// fbow's Vocabulary::setParams arithmetic.
Layout layout_for(std::uint64_t alignment, std::uint64_t branching, std::uint64_t code_size) {
  Layout layout;
  layout.stride = round_up(code_size, alignment);
  layout.feature_offset = round_up(8, alignment);
  layout.child_offset = layout.feature_offset + branching * layout.stride;
  layout.block_size = round_up(layout.feature_offset + branching * (layout.stride + 8), alignment);
  return layout;
}

}  // namespace

ParsedVocabulary parse_fbow(const std::uint8_t* data, std::size_t size, const std::string& name) {
  ByteReader in(data, size, name);
  if (in.read<std::uint64_t>("the signature") != kSignature)
    in.fail("not an fbow vocabulary: wrong signature");
  const std::uint8_t* params = in.take(kParamsSize, "the parameter block");
  const std::uint32_t alignment = load_le<std::uint32_t>(params + 52);
  const std::uint32_t block_count = load_le<std::uint32_t>(params + 56);
  const std::uint64_t stride = load_le<std::uint64_t>(params + 64);
  const std::uint64_t block_size = load_le<std::uint64_t>(params + 72);
  const std::uint64_t feature_offset = load_le<std::uint64_t>(params + 80);
  const std::uint64_t child_offset = load_le<std::uint64_t>(params + 88);
  const std::uint64_t total_size = load_le<std::uint64_t>(params + 96);
  const std::int32_t type = load_le<std::int32_t>(params + 104);
  const std::int32_t code_size = load_le<std::int32_t>(params + 108);
  const std::uint32_t branching = load_le<std::uint32_t>(params + 112);
  if (type != 0)
    in.fail("descriptors of OpenCV type " + std::to_string(type) +
            ": only binary descriptors (CV_8U) are supported");
  if (code_size < 1 || static_cast<std::size_t>(code_size) > kMaxCodeSize)
    in.fail("descriptor size " + std::to_string(code_size) + " is outside 1.." +
            std::to_string(kMaxCodeSize));
  if (branching < 1 || branching > kMaxBranching)
    in.fail("branching factor k = " + std::to_string(branching) + " is outside 1..255");
  if (alignment < 1 || alignment > 4096)
    in.fail("alignment " + std::to_string(alignment) + " is outside 1..4096");
  const Layout layout = layout_for(alignment, branching, static_cast<std::uint64_t>(code_size));
  if (stride != layout.stride || feature_offset != layout.feature_offset ||
      child_offset != layout.child_offset || block_size != layout.block_size)
    in.fail("inconsistent block layout in the parameter block (corrupt header)");
  if (block_count < 1) in.fail("no blocks");
  if (total_size != std::uint64_t{block_count} * block_size || total_size != in.remaining())
    in.fail("the header announces " + std::to_string(block_count) + " blocks of " +
            std::to_string(block_size) + " bytes but " + std::to_string(in.remaining()) +
            " bytes follow it" + (total_size > in.remaining() ? " (truncated)" : ""));
  const std::uint8_t* blocks = in.take(total_size, "the blocks");

  ParsedVocabulary parsed;
  VocabularyTree& tree = parsed.tree;
  tree.code_size = static_cast<std::size_t>(code_size);
  tree.branching = branching;
  tree.weighting = Weighting::kTfIdf;
  tree.scoring = Scoring::kL1;
  tree.parent.push_back(0);
  tree.descriptors.assign(tree.code_size, 0);
  tree.weights.push_back(0.0f);
  std::vector<std::uint32_t> depth{0};
  std::vector<std::pair<std::uint32_t, std::uint32_t>> words;
  std::vector<std::uint8_t> visited(block_count, 0);
  // Depth-first with each node's children numbered together: DBoW2's order.
  struct Pending {
    std::uint32_t block;
    NodeId node;
  };
  std::vector<Pending> stack{{0, 0}};
  visited[0] = 1;
  while (!stack.empty()) {
    const Pending pending = stack.back();
    stack.pop_back();
    const std::uint8_t* block = blocks + std::uint64_t{pending.block} * block_size;
    const std::string where = "block " + std::to_string(pending.block) + ": ";
    const std::uint16_t children = load_le<std::uint16_t>(block);
    if (children < 1 || children > branching)
      in.fail(where + std::to_string(children) + " children, expected 1.." +
              std::to_string(branching));
    const NodeId first = static_cast<NodeId>(tree.parent.size());
    const std::size_t stack_mark = stack.size();
    for (std::uint32_t c = 0; c < children; ++c) {
      const NodeId node = first + c;
      const std::uint8_t* info = block + child_offset + std::uint64_t{c} * 8;
      const std::uint32_t link = load_le<std::uint32_t>(info);
      const float weight = load_le<float>(info + 4);
      tree.parent.push_back(pending.node);
      depth.push_back(depth[pending.node] + 1);
      const std::uint8_t* feature = block + feature_offset + std::uint64_t{c} * stride;
      tree.descriptors.insert(tree.descriptors.end(), feature, feature + code_size);
      if (link & kLeafBit) {
        if (!std::isfinite(weight)) in.fail(where + "a word weight is not finite");
        tree.weights.push_back(weight);
        words.emplace_back(link & ~kLeafBit, node);
      } else {
        tree.weights.push_back(0.0f);
        if (link >= block_count || visited[link])
          in.fail(where + "child block " + std::to_string(link) +
                  (link >= block_count ? " does not exist"
                                       : " is reached twice (cycle or shared block)"));
        visited[link] = 1;
        stack.push_back({link, node});
      }
      if (depth.back() > kMaxLevels)
        in.fail(where + "the tree is deeper than " + std::to_string(kMaxLevels) + " levels");
    }
    std::reverse(stack.begin() + static_cast<std::ptrdiff_t>(stack_mark), stack.end());
  }
  for (std::uint32_t b = 0; b < block_count; ++b)
    if (!visited[b]) in.fail("block " + std::to_string(b) + " is not reachable from the root");
  std::uint32_t levels = 0;
  for (const std::uint32_t d : depth) levels = std::max(levels, d);
  tree.levels = levels;
  parsed.word_ids_match = check_word_list(tree, words, name);
  return parsed;
}

std::vector<std::uint8_t> format_fbow(const VocabularyTree& tree) {
  const ChildLists children = child_lists(tree);
  const std::size_t nodes = tree.node_count();
  const auto is_leaf = [&](std::size_t node) {
    return children.first[node] == children.first[node + 1];
  };
  // Blocks: inner nodes in node order (the root first), as fbow's converter.
  std::vector<std::uint32_t> block_of(nodes, 0);
  std::uint32_t block_count = 0;
  for (std::size_t node = 0; node < nodes; ++node)
    if (!is_leaf(node)) block_of[node] = block_count++;
  std::vector<std::uint32_t> word_of(nodes, 0);
  std::uint32_t words = 0;
  for (std::size_t node = 1; node < nodes; ++node)
    if (is_leaf(node)) word_of[node] = words++;

  const Layout layout = layout_for(kWriteAlignment, tree.branching, tree.code_size);
  const std::uint64_t total_size = layout.block_size * block_count;
  std::vector<std::uint8_t> out(8 + kParamsSize + total_size, 0);
  std::uint8_t* params = out.data() + 8;
  store_le(out.data(), kSignature);
  const char* desc_name = tree.code_size == 32 ? "orb" : "binary";
  std::memcpy(params, desc_name, std::strlen(desc_name));
  store_le(params + 52, kWriteAlignment);
  store_le(params + 56, block_count);
  store_le(params + 64, layout.stride);
  store_le(params + 72, layout.block_size);
  store_le(params + 80, layout.feature_offset);
  store_le(params + 88, layout.child_offset);
  store_le(params + 96, total_size);
  store_le(params + 104, std::int32_t{0});
  store_le(params + 108, static_cast<std::int32_t>(tree.code_size));
  store_le(params + 112, tree.branching);
  std::uint8_t* blocks = params + kParamsSize;
  for (std::size_t node = 0; node < nodes; ++node) {
    if (is_leaf(node)) continue;
    std::uint8_t* block = blocks + std::uint64_t{block_of[node]} * layout.block_size;
    const std::uint32_t begin = children.first[node], end = children.first[node + 1];
    bool all_leaves = true;
    for (std::uint32_t c = begin; c < end; ++c) {
      const NodeId child = children.child[c];
      std::memcpy(block + layout.feature_offset + (c - begin) * layout.stride,
                  tree.descriptors.data() + child * tree.code_size, tree.code_size);
      std::uint8_t* info = block + layout.child_offset + std::uint64_t{c - begin} * 8;
      if (is_leaf(child)) {
        store_le(info, word_of[child] | kLeafBit);
        store_le(info + 4, tree.weights[child]);
      } else {
        store_le(info, block_of[child]);
        all_leaves = false;
      }
    }
    store_le(block, static_cast<std::uint16_t>(end - begin));
    store_le(block + 2, static_cast<std::uint16_t>(all_leaves ? 1 : 0));
    store_le(block + 4, static_cast<std::uint32_t>(node));
  }
  return out;
}

}  // namespace binbow::detail
