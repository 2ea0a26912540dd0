// Shared fixtures for the benchmarks: large synthetic vocabularies and
// descriptor sets, built once per process.
#pragma once

#include <cstdint>
#include <random>
#include <string>

#include "binbow/vocabulary.h"
#include "support/random_tree.h"

namespace binbow::bench {

// A complete k-ary tree of depth L with random node descriptors and weights:
// k=10, L=6 gives 1,000,000 words and 1,111,111 nodes, the paper's size. The
// descent cost (k distances per level, one cache miss per level) does not
// depend on the descriptor values, so it times transform like a trained tree.
inline Vocabulary full_random_vocabulary(std::uint32_t k, std::uint32_t levels,
                                         std::size_t code_size = 32, std::uint64_t seed = 42) {
  return Vocabulary::from_tree(test::complete_random_tree(k, levels, code_size, seed));
}

inline DescriptorMatrix random_descriptors(std::size_t rows, std::size_t code_size,
                                           std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  DescriptorMatrix m(rows, code_size);
  for (std::size_t i = 0; i < rows * code_size; ++i) m.data()[i] = static_cast<std::uint8_t>(rng());
  return m;
}

}  // namespace binbow::bench
