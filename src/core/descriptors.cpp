#include "binbow/descriptors.h"

#include <algorithm>
#include <string>

#include "binbow/error.h"
#include "core/kernels.h"

namespace binbow {

void DescriptorMatrix::append(const std::uint8_t* descriptor) {
  const std::size_t at = data_.size();
  data_.resize(at + code_size_);
  std::copy_n(descriptor, code_size_, data_.data() + at);
  ++rows_;
}

void DescriptorMatrix::append(const DescriptorView& other) {
  if (other.rows == 0) return;
  if (other.code_size != code_size_)
    throw InvalidArgument("cannot append " + std::to_string(other.code_size) +
                          "-byte descriptors to a matrix of " + std::to_string(code_size_) +
                          "-byte descriptors");
  data_.insert(data_.end(), other.data, other.data + other.rows * other.code_size);
  rows_ += other.rows;
}

std::uint32_t hamming_distance(const std::uint8_t* a, const std::uint8_t* b,
                               std::size_t code_size) {
  return detail::kernels().hamming(a, b, code_size);
}

void nearest_neighbors(const DescriptorView& queries, const DescriptorView& candidates,
                       std::uint32_t* best_index, std::uint32_t* best_distance) {
  if (queries.rows == 0) return;
  if (candidates.rows == 0) throw InvalidArgument("nearest_neighbors: no candidates");
  if (queries.code_size != candidates.code_size)
    throw InvalidArgument("nearest_neighbors: queries have " + std::to_string(queries.code_size) +
                          " bytes per descriptor, candidates " +
                          std::to_string(candidates.code_size));
  detail::kernels().nearest(queries.data, queries.rows, candidates.data, candidates.rows,
                            queries.code_size, best_index, best_distance);
}

const char* hamming_kernel_name() {
  return detail::kernels().name;
}

std::vector<std::string> supported_hamming_kernels() {
  std::vector<std::string> names;
  for (const detail::Kernels* k : detail::supported_kernels()) names.emplace_back(k->name);
  return names;
}

std::vector<CpuFeature> cpu_features() {
  std::vector<CpuFeature> features;
  for (const detail::CpuFeatureFlag& f : detail::kernel_cpu_features())
    features.push_back({f.name, f.present});
  return features;
}

}  // namespace binbow
