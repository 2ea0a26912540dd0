// Binary descriptors: fixed-length bit strings stored as contiguous rows of
// bytes (row-major, `code_size` bytes per row), compared by Hamming distance.
//
// 32 bytes (ORB, BRIEF-256) and 64 bytes (BRISK, ...) have specialised popcount
// kernels; any other length works through a generic one. Bit i of a descriptor
// is bit (i % 8) of byte (i / 8), counting from the least significant bit,
// which is the layout of OpenCV's and DBoW2's binary descriptors.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace binbow {

// Non-owning view of `rows` descriptors of `code_size` bytes each.
struct DescriptorView {
  const std::uint8_t* data = nullptr;
  std::size_t rows = 0;
  std::size_t code_size = 0;

  const std::uint8_t* row(std::size_t i) const { return data + i * code_size; }
  bool empty() const noexcept { return rows == 0; }
  // A view of rows [first, first + count).
  DescriptorView slice(std::size_t first, std::size_t count) const {
    return {data + first * code_size, count, code_size};
  }
};

// Owning, contiguous matrix of descriptors.
class DescriptorMatrix {
 public:
  DescriptorMatrix() = default;
  explicit DescriptorMatrix(std::size_t code_size) : code_size_(code_size) {}
  // `rows` zero-filled descriptors.
  DescriptorMatrix(std::size_t rows, std::size_t code_size)
      : data_(rows * code_size), rows_(rows), code_size_(code_size) {}
  // Copies `rows * code_size` bytes from `data`.
  DescriptorMatrix(const std::uint8_t* data, std::size_t rows, std::size_t code_size)
      : data_(data, data + rows * code_size), rows_(rows), code_size_(code_size) {}

  std::size_t rows() const noexcept { return rows_; }
  std::size_t code_size() const noexcept { return code_size_; }
  bool empty() const noexcept { return rows_ == 0; }
  std::uint8_t* data() noexcept { return data_.data(); }
  const std::uint8_t* data() const noexcept { return data_.data(); }
  std::uint8_t* row(std::size_t i) { return data_.data() + i * code_size_; }
  const std::uint8_t* row(std::size_t i) const { return data_.data() + i * code_size_; }

  // Appends one descriptor of code_size() bytes.
  void append(const std::uint8_t* descriptor);
  // Appends every row of `other`, which must have the same code size.
  void append(const DescriptorView& other);
  void reserve(std::size_t rows) { data_.reserve(rows * code_size_); }
  void resize(std::size_t rows) {
    data_.resize(rows * code_size_);
    rows_ = rows;
  }
  void clear() noexcept {
    data_.clear();
    rows_ = 0;
  }

  DescriptorView view() const noexcept { return {data_.data(), rows_, code_size_}; }
  operator DescriptorView() const noexcept { return view(); }  // NOLINT: implicit by design

 private:
  std::vector<std::uint8_t> data_;
  std::size_t rows_ = 0;
  std::size_t code_size_ = 0;
};

// Number of differing bits between two descriptors of `code_size` bytes.
// Uses hardware popcount when the CPU has it (checked once at run time).
std::uint32_t hamming_distance(const std::uint8_t* a, const std::uint8_t* b, std::size_t code_size);

// For each of the `queries.rows` descriptors, the index of the nearest row of
// `candidates` (lowest index on ties) and its distance. Output arrays hold
// queries.rows elements. Throws InvalidArgument if the code sizes differ or
// `candidates` is empty.
void nearest_neighbors(const DescriptorView& queries, const DescriptorView& candidates,
                       std::uint32_t* best_index, std::uint32_t* best_distance);

// Name of the Hamming kernel set chosen at run time for this CPU, the fastest it
// supports: on x86-64 "avx512" (AVX-512 VPOPCNTDQ), "avx2" (256-bit nibble
// lookups), "popcnt" (hardware popcount) or "generic" (portable bit counting);
// on aarch64 "neon" or "generic". The environment variable
// BINBOW_HAMMING_KERNEL, read once on first use, forces one of the supported
// sets instead (for measurements and tests; every set gives the same results).
// Transform, database and matching speed depend on it, so benchmarks should
// name it (`binbow info --system` prints it). Throws InvalidArgument naming the
// variable, its value and the supported sets if BINBOW_HAMMING_KERNEL names a
// set this CPU cannot run, as does every function that computes distances.
const char* hamming_kernel_name();

// Every kernel set this CPU can run, from the portable one to the fastest (the
// one chosen unless BINBOW_HAMMING_KERNEL says otherwise).
std::vector<std::string> supported_hamming_kernels();

// A CPU feature that decides which kernel set can run.
struct CpuFeature {
  const char* name;  // as GCC's __builtin_cpu_supports spells it, e.g. "avx512vpopcntdq"
  bool present;
};

// The CPU features binbow's kernel choice depends on, in a fixed order
// (popcnt, avx2, avx512f, avx512vpopcntdq); empty on other processors (NEON,
// which the aarch64 kernels use, is part of every aarch64 CPU).
std::vector<CpuFeature> cpu_features();

}  // namespace binbow
