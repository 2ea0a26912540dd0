// Random vocabulary trees in DBoW2's node order (depth first, the children of
// a node contiguous), with random descriptors and leaf weights, for the tests
// and benchmarks of file formats.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "binbow/vocabulary.h"

namespace binbow::test {

// `child_count(depth, rng)` gives the number of children of a node at `depth`
// (0: the node is a leaf); nodes at depth `levels` are always leaves.
template <class ChildCount>
VocabularyTree random_tree(std::uint32_t branching, std::uint32_t levels, std::size_t code_size,
                           std::mt19937_64& rng, ChildCount child_count) {
  VocabularyTree tree;
  tree.code_size = code_size;
  tree.branching = branching;
  tree.levels = levels;
  tree.weighting = Weighting::kTfIdf;
  tree.scoring = Scoring::kL1;
  tree.parent.push_back(0);
  std::vector<std::uint32_t> depth{0};
  std::vector<NodeId> stack{0};
  while (!stack.empty()) {
    const NodeId node = stack.back();
    stack.pop_back();
    if (depth[node] == levels) continue;
    const std::uint32_t count = child_count(depth[node], rng);
    const NodeId first = static_cast<NodeId>(tree.parent.size());
    for (std::uint32_t c = 0; c < count; ++c) {
      tree.parent.push_back(node);
      depth.push_back(depth[node] + 1);
    }
    for (std::uint32_t c = count; c-- > 0;) stack.push_back(first + c);
  }
  const std::size_t nodes = tree.parent.size();
  tree.descriptors.resize(nodes * code_size);
  for (std::size_t i = code_size; i < tree.descriptors.size(); ++i)
    tree.descriptors[i] = static_cast<std::uint8_t>(rng());
  std::vector<std::uint8_t> inner(nodes, 0);
  for (std::size_t i = 1; i < nodes; ++i) inner[tree.parent[i]] = 1;
  tree.weights.assign(nodes, 0.0f);
  std::uniform_real_distribution<float> weight(0.0f, 12.0f);
  for (std::size_t i = 1; i < nodes; ++i)
    if (!inner[i]) tree.weights[i] = weight(rng);
  return tree;
}

// Uneven branching: below the root a node is a leaf with probability
// `early_leaf`, else it has all `branching` children (70%) or 1..branching.
inline VocabularyTree random_tree(std::uint32_t branching, std::uint32_t levels,
                                  std::size_t code_size, std::mt19937_64& rng,
                                  double early_leaf = 0.1) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<std::uint32_t> children(1, branching);
  return random_tree(branching, levels, code_size, rng,
                     [&](std::uint32_t depth, std::mt19937_64& r) -> std::uint32_t {
                       if (depth != 0 && unit(r) < early_leaf) return 0;
                       return unit(r) < 0.7 ? branching : children(r);
                     });
}

}  // namespace binbow::test
