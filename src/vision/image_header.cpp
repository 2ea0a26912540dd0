#include "vision/image_header.h"

#include <algorithm>

namespace binbow::vision {
namespace {

std::uint32_t big_endian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}
std::uint32_t big_endian16(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 8) | std::uint32_t{p[1]};
}

std::optional<ImageDimensions> png_dimensions(const std::vector<std::uint8_t>& bytes) {
  // Signature (8 bytes), IHDR length (4), "IHDR" (4), width (4), height (4).
  if (bytes.size() < 24 || bytes[12] != 'I' || bytes[13] != 'H' || bytes[14] != 'D' ||
      bytes[15] != 'R') {
    return std::nullopt;
  }
  return ImageDimensions{big_endian32(&bytes[16]), big_endian32(&bytes[20])};
}

// Walks the marker segments up to the first start-of-frame.
std::optional<ImageDimensions> jpeg_dimensions(const std::vector<std::uint8_t>& bytes) {
  std::size_t at = 2;  // after SOI
  while (at + 4 <= bytes.size()) {
    if (bytes[at] != 0xFF) return std::nullopt;
    const std::uint8_t marker = bytes[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0xD8 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
      at += 2;  // markers without a length
      continue;
    }
    if (marker == 0xDA || marker == 0xD9) return std::nullopt;  // scan before any frame
    const std::size_t length = big_endian16(&bytes[at + 2]);
    const bool start_of_frame =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (start_of_frame) {
      // length (2), precision (1), height (2), width (2)
      if (at + 9 > bytes.size()) return std::nullopt;
      return ImageDimensions{big_endian16(&bytes[at + 7]), big_endian16(&bytes[at + 5])};
    }
    if (length < 2) return std::nullopt;
    at += 2 + length;
  }
  return std::nullopt;
}

}  // namespace

std::optional<ImageDimensions> declared_dimensions(const std::vector<std::uint8_t>& bytes) {
  static constexpr std::uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (bytes.size() >= 8 && std::equal(kPngSignature, kPngSignature + 8, bytes.begin())) {
    return png_dimensions(bytes);
  }
  if (bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8) return jpeg_dimensions(bytes);
  return std::nullopt;
}

}  // namespace binbow::vision
