// Image dimensions read from a file's header before decoding, so that a small
// file declaring a huge image is refused instead of allocating gigabytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace binbow::vision {

struct ImageDimensions {
  std::uint64_t width = 0, height = 0;
  const char* format = "";  // "png", "jpeg", "tiff", "bmp", "webp", "pnm", ...
  // PNG and JPEG: the compression ratio is bounded (max_pixels_for_file_size).
  bool ratio_bounded = false;
  // TIFF: the strip or tile that OpenCV's decoder buffers at once, which a
  // header may declare larger than the image (0 x 0 for other formats).
  std::uint64_t block_width = 0, block_height = 0;
};

// Width and height declared by the header of every still-image format this
// OpenCV decodes by content: PNG, JPEG, TIFF (classic and BigTIFF, first
// directory), BMP, WebP (VP8, VP8L, VP8X canvas), PBM/PGM/PPM/PAM, PFM, Sun
// raster, Radiance HDR, OpenEXR (data window) and JPEG 2000 (.jp2 and raw
// codestream, from the codestream's SIZ marker, at most 4 components).
// nullopt for any other content (DICOM, unknown, a header too short or
// malformed to say): such a file cannot be bounded before decoding.
std::optional<ImageDimensions> declared_dimensions(const std::uint8_t* data, std::size_t size);
inline std::optional<ImageDimensions> declared_dimensions(const std::vector<std::uint8_t>& bytes) {
  return declared_dimensions(bytes.data(), bytes.size());
}

// The largest pixel count a PNG or JPEG file of `file_size` bytes may
// declare: deflate and JPEG's entropy coding cannot compress 8-bit images by
// more than about 1:1032, plus slack for tiny files.
inline std::uint64_t max_pixels_for_file_size(std::size_t file_size) {
  return (std::uint64_t{1} << 22) + 1100 * static_cast<std::uint64_t>(file_size);
}

// "WIDTHxHEIGHT".
std::string describe_size(std::uint64_t width, std::uint64_t height);

// Throws FileError naming `path` when `width` x `height` is 0 or above
// `max_pixels`; `what` says whose size it is ("image header", "decoded image").
void check_pixel_count(const std::string& path, const char* what, std::uint64_t width,
                       std::uint64_t height, std::uint64_t max_pixels);

// The first checks of the content `bytes` of image file `path` before it is
// decoded: not empty, of a size its header declares, at most `max_pixels`.
// Throws FileError naming `path`; returns the size.
ImageDimensions check_image_header(const std::string& path, const std::string& bytes,
                                   std::uint64_t max_pixels);
// The checks of what a decoder would allocate beyond the image: a TIFF strip
// or tile of at most `max_pixels`, and no more pixels than a PNG or JPEG of
// `file_size` bytes can hold.
void check_image_allocation(const std::string& path, const ImageDimensions& declared,
                            std::size_t file_size, std::uint64_t max_pixels);

}  // namespace binbow::vision
