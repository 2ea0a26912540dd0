// Hot kernels, compiled once per instruction set (kernels_generic.cpp,
// kernels_popcnt.cpp, kernels_avx2.cpp, kernels_avx512.cpp, kernels_neon.cpp)
// from kernels_impl.h and selected once at run time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace binbow::detail {

inline constexpr std::uint32_t kLeafBit = 0x80000000u;

// The flat tree as the descent kernel reads it. Children of a node are
// contiguous: links[n] is the first child of inner node n, child_counts[n] their
// number; a leaf has child_counts[n] == 0 and links[n] == word | kLeafBit.
struct TreeView {
  const std::uint8_t* descriptors = nullptr;  // node_count × code_size
  const std::uint32_t* links = nullptr;
  const std::uint8_t* child_counts = nullptr;
  std::size_t code_size = 0;
};

struct Kernels {
  const char* name;
  std::uint32_t (*hamming)(const std::uint8_t* a, const std::uint8_t* b, std::size_t code_size);
  // For each of the n queries (contiguous rows), the index in [0, count) of the
  // nearest of `count` contiguous candidate rows (lowest index on ties) and its
  // distance. best_distance may be null.
  void (*nearest)(const std::uint8_t* queries, std::size_t n, const std::uint8_t* candidates,
                  std::size_t count, std::size_t code_size, std::uint32_t* best_index,
                  std::uint32_t* best_distance);
  // The distance of one query to each of `count` rows: rows + r × code_size
  // for r = 0..count-1, or for r = indices[i] when indices is not null
  // (rows scattered in a matrix, e.g. the words of an online-vocabulary
  // leaf). distances[i] receives the i-th.
  void (*distances)(const std::uint8_t* query, const std::uint8_t* rows,
                    const std::uint32_t* indices, std::size_t count, std::size_t code_size,
                    std::uint32_t* distances);
  // Greedy descent of n descriptors from the root: words[i] receives the word.
  // When level_nodes is not null, level_nodes[i] receives the node at depth
  // `level_depth` on the path, or the leaf if it is shallower.
  void (*descend)(const TreeView& tree, const std::uint8_t* queries, std::size_t n,
                  std::uint32_t* words, std::uint32_t* level_nodes, std::uint32_t level_depth);
};

// The environment variable that forces a kernel set by name.
inline constexpr const char* kKernelVariable = "BINBOW_HAMMING_KERNEL";

// The kernels in use (chosen on first call, thread-safe): select_kernels()
// of BINBOW_HAMMING_KERNEL's value.
const Kernels& kernels();
// The supported set named `requested`, or the fastest when it is null or
// empty. Throws InvalidArgument naming the variable, the value and the
// supported sets otherwise.
const Kernels& select_kernels(const char* requested);
// Kernels without hardware popcount, for tests that compare implementations.
const Kernels& generic_kernels();
// Every kernel set this CPU can run, from the portable one to the fastest.
std::vector<const Kernels*> supported_kernels();

struct CpuFeatureFlag {
  const char* name;
  bool present;
};
// The CPU features supported_kernels() checks; empty without run-time dispatch.
std::vector<CpuFeatureFlag> kernel_cpu_features();

}  // namespace binbow::detail
