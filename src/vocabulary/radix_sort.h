// Stable LSD radix sort of 32-bit keys (optionally with a payload), 8 bits per
// pass and only as many passes as the largest key needs: for the ~1000 word
// ids of one image it is several times faster than std::sort.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace binbow::detail {

// Sorts keys[0..n) (and values alongside, if not null) using the temporary
// buffers; stable, so equal keys keep their order.
inline void radix_sort(std::vector<std::uint32_t>& keys, std::vector<std::uint32_t>* values,
                       std::vector<std::uint32_t>& key_buffer,
                       std::vector<std::uint32_t>& value_buffer) {
  const std::size_t n = keys.size();
  if (n < 2) return;
  const std::uint32_t max_key = *std::max_element(keys.begin(), keys.end());
  key_buffer.resize(n);
  if (values != nullptr) value_buffer.resize(n);
  for (unsigned shift = 0; shift < 32 && (max_key >> shift) != 0; shift += 8) {
    std::uint32_t count[257] = {};
    for (std::size_t i = 0; i < n; ++i) ++count[((keys[i] >> shift) & 0xffu) + 1];
    for (int d = 0; d < 256; ++d) count[d + 1] += count[d];
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t slot = count[(keys[i] >> shift) & 0xffu]++;
      key_buffer[slot] = keys[i];
      if (values != nullptr) value_buffer[slot] = (*values)[i];
    }
    keys.swap(key_buffer);
    if (values != nullptr) values->swap(value_buffer);
  }
}

}  // namespace binbow::detail
