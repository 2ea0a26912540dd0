// Shared fixtures for the benchmarks: large synthetic vocabularies and
// descriptor sets, built once per process.
#pragma once

#include <cstdint>
#include <random>
#include <string>

#include "binbow/vocabulary.h"

namespace binbow::bench {

// A complete k-ary tree of depth L with random node descriptors and weights:
// k=10, L=6 gives 1,000,000 words and 1,111,111 nodes, the paper's size. The
// descent cost (k distances per level, one cache miss per level) does not
// depend on the descriptor values, so it times transform like a trained tree.
inline Vocabulary full_random_vocabulary(std::uint32_t k, std::uint32_t levels,
                                         std::size_t code_size = 32, std::uint64_t seed = 42) {
  std::mt19937_64 rng(seed);
  VocabularyTree t;
  t.code_size = code_size;
  t.branching = k;
  t.levels = levels;
  std::size_t level_begin = 0, level_size = 1;
  t.parent.push_back(0);
  for (std::uint32_t depth = 0; depth < levels; ++depth) {
    for (std::size_t i = 0; i < level_size; ++i)
      for (std::uint32_t c = 0; c < k; ++c)
        t.parent.push_back(static_cast<NodeId>(level_begin + i));
    level_begin += level_size;
    level_size *= k;
  }
  t.descriptors.resize(t.parent.size() * code_size);
  for (auto& b : t.descriptors) b = static_cast<std::uint8_t>(rng());
  std::uniform_real_distribution<float> weight(0.5f, 5.0f);
  t.weights.resize(t.parent.size());
  for (auto& w : t.weights) w = weight(rng);
  return Vocabulary::from_tree(t);
}

inline DescriptorMatrix random_descriptors(std::size_t rows, std::size_t code_size,
                                           std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  DescriptorMatrix m(rows, code_size);
  for (std::size_t i = 0; i < rows * code_size; ++i) m.data()[i] = static_cast<std::uint8_t>(rng());
  return m;
}

}  // namespace binbow::bench
