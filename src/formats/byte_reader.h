// Bounds-checked little-endian reading of a binary file in memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "binbow/error.h"

namespace binbow::detail {

class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size, const std::string& name)
      : data_(data), size_(size), name_(name) {}

  std::size_t offset() const noexcept { return offset_; }
  std::size_t remaining() const noexcept { return size_ - offset_; }

  // Throws "truncated" naming `what` when fewer than `count` bytes remain.
  const std::uint8_t* take(std::size_t count, const char* what) {
    if (count > remaining())
      throw FileError(name_, std::string("truncated: ") + what + " needs " + std::to_string(count) +
                                 " bytes at offset " + std::to_string(offset_) + ", the file has " +
                                 std::to_string(remaining()) + " left");
    const std::uint8_t* at = data_ + offset_;
    offset_ += count;
    return at;
  }
  template <class T>
  T read(const char* what) {
    T value;
    std::memcpy(&value, take(sizeof(T), what), sizeof(T));
    return value;
  }
  [[noreturn]] void fail(const std::string& problem) const { throw FileError(name_, problem); }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
  const std::string& name_;
};

}  // namespace binbow::detail
