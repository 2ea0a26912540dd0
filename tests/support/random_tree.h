// Random vocabulary trees for the tests and benchmarks: in DBoW2's node order
// (depth first, the children of a node contiguous) for the file formats, and
// complete k-ary trees in breadth-first order for timings and for tests that
// supply their own BoW vectors.
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

// A complete k-ary tree of depth `levels`, breadth first, with random node
// descriptors and weights in [0.5, 5): k=10, levels=6 gives 1,000,000 words,
// the paper's size. Descent costs the same as in a trained tree (k distances
// and one cache miss per level), whatever the descriptor values.
inline VocabularyTree complete_random_tree(std::uint32_t k, std::uint32_t levels,
                                           std::size_t code_size, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  VocabularyTree tree;
  tree.code_size = code_size;
  tree.branching = k;
  tree.levels = levels;
  std::size_t level_begin = 0, level_size = 1;
  tree.parent.push_back(0);
  for (std::uint32_t depth = 0; depth < levels; ++depth) {
    for (std::size_t i = 0; i < level_size; ++i)
      for (std::uint32_t c = 0; c < k; ++c)
        tree.parent.push_back(static_cast<NodeId>(level_begin + i));
    level_begin += level_size;
    level_size *= k;
  }
  tree.descriptors.resize(tree.parent.size() * code_size);
  for (auto& b : tree.descriptors) b = static_cast<std::uint8_t>(rng());
  std::uniform_real_distribution<float> weight(0.5f, 5.0f);
  tree.weights.resize(tree.parent.size());
  for (auto& w : tree.weights) w = weight(rng);
  return tree;
}

}  // namespace binbow::test
