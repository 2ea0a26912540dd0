// Explicit little-endian encoding for binbow's binary files.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace binbow::detail {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "binbow maps its files in place and needs a little-endian CPU");

template <class T>
inline void put_le(std::vector<std::uint8_t>& out, T value) {
  const std::size_t at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &value, sizeof(T));
}

template <class T>
inline void store_le(std::uint8_t* at, T value) {
  std::memcpy(at, &value, sizeof(T));
}

template <class T>
inline T load_le(const std::uint8_t* at) {
  T value;
  std::memcpy(&value, at, sizeof(T));
  return value;
}

}  // namespace binbow::detail
