#include "formats/tree_checks.h"

#include <cstdint>

#include "binbow/error.h"
#include "formats/codecs.h"
#include "vocabulary/word_weights.h"

namespace binbow::detail {

void check_header_values(const std::string& name, const std::string& where, std::int64_t branching,
                         std::int64_t levels, std::int64_t scoring, std::int64_t weighting) {
  auto fail = [&](const std::string& problem) { throw FileError(name, where + ": " + problem); };
  if (branching < 1 || branching > kMaxBranching)
    fail("branching factor k = " + std::to_string(branching) + " is outside 1.." +
         std::to_string(kMaxBranching));
  if (levels < 1 || levels > kMaxLevels)
    fail("depth L = " + std::to_string(levels) + " is outside 1.." + std::to_string(kMaxLevels));
  if (scoring < 0 || scoring > static_cast<int>(Scoring::kDotProduct))
    fail("scoring type " + std::to_string(scoring) + " is outside 0..5");
  if (weighting < 0 || weighting > static_cast<int>(Weighting::kBinary))
    fail("weighting type " + std::to_string(weighting) + " is outside 0..3");
}

void check_listed_tree(VocabularyTree& tree, const std::vector<std::uint8_t>& leaf_flags,
                       const std::string& name, const char* unit, std::size_t unit_offset) {
  const std::size_t node_count = tree.node_count();
  const auto fail = [&](std::size_t node, const std::string& problem) {
    throw FileError(name,
                    std::string(unit) + " " + std::to_string(node + unit_offset) + ": " + problem);
  };
  std::vector<std::uint8_t> has_children(node_count, 0);
  for (std::size_t node = 1; node < node_count; ++node) {
    const NodeId parent = tree.parent[node];
    if (parent >= node)
      fail(node, "parent id " + std::to_string(parent) + " of node " + std::to_string(node) +
                     " is not an earlier node");
    has_children[parent] = 1;
  }
  for (std::size_t node = 1; node < node_count; ++node) {
    if (leaf_flags[node] && has_children[node])
      fail(node, "node " + std::to_string(node) + " is marked as a leaf but has children");
    if (!leaf_flags[node] && !has_children[node])
      fail(node,
           "node " + std::to_string(node) + " is marked as an inner node but has no children");
    if (!leaf_flags[node]) tree.weights[node] = 0.0f;
  }
}

bool check_word_list(VocabularyTree& tree,
                     const std::vector<std::pair<std::uint32_t, std::uint32_t>>& words,
                     const std::string& name) {
  constexpr std::uint32_t kNone = UINT32_MAX;
  const std::size_t node_count = tree.node_count();
  std::vector<std::uint8_t> has_children(node_count, 0);
  for (std::size_t node = 1; node < node_count; ++node) has_children[tree.parent[node]] = 1;
  std::vector<std::uint32_t> leaf_rank(node_count, kNone);
  std::uint32_t leaves = 0;
  for (std::size_t node = 1; node < node_count; ++node) {
    if (has_children[node])
      tree.weights[node] = 0.0f;
    else
      leaf_rank[node] = leaves++;
  }
  if (words.size() != leaves)
    throw FileError(name, "the word list has " + std::to_string(words.size()) +
                              " entries but the tree has " + std::to_string(leaves) + " leaves");
  bool ids_match = true;
  std::vector<std::uint8_t> seen_word(leaves, 0), seen_node(node_count, 0);
  for (const auto& [word, node] : words) {
    if (word >= leaves || seen_word[word])
      throw FileError(name, "word id " + std::to_string(word) + " is repeated or outside 0.." +
                                std::to_string(leaves - 1));
    if (node >= node_count || leaf_rank[node] == kNone || seen_node[node])
      throw FileError(name, "word " + std::to_string(word) + ": node id " + std::to_string(node) +
                                " is not a distinct leaf of the tree");
    seen_word[word] = seen_node[node] = 1;
    if (leaf_rank[node] != word) ids_match = false;
  }
  return ids_match;
}

void check_word_weights(const VocabularyTree& tree, const std::string& name) {
  // Inner nodes weigh 0, so the words' weights decide alone: a negative one
  // is found among all nodes' weights, and "all 0" is the same over both.
  const std::string problem = word_weights_problem(
      tree.weights.size(), [&](std::size_t node) { return tree.weights[node]; }, "node");
  if (!problem.empty()) throw FileError(name, problem);
}

}  // namespace binbow::detail
