// Image dimensions read from a file's header before decoding, so that a small
// file declaring a huge image is refused instead of allocating gigabytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace binbow::vision {

struct ImageDimensions {
  std::uint64_t width = 0, height = 0;
};

// Width and height declared by a PNG (IHDR) or JPEG (first SOF marker)
// header; nullopt for other formats or a header too short or malformed to
// say (the decoder then reports the problem).
std::optional<ImageDimensions> declared_dimensions(const std::vector<std::uint8_t>& bytes);

// The largest pixel count a file of `file_size` bytes may declare: PNG's
// deflate and JPEG's entropy coding cannot compress 8-bit images by more than
// about 1:1032, plus slack for tiny files.
inline std::uint64_t max_pixels_for_file_size(std::size_t file_size) {
  return (std::uint64_t{1} << 22) + 1100 * static_cast<std::uint64_t>(file_size);
}

}  // namespace binbow::vision
