// JPEG decoding with libjpeg, damage included. OpenCV 4.6 decodes a damaged
// JPEG (cut short, corrupt entropy data) into a partly grey image and leaves
// only libjpeg's warning on stderr; here libjpeg's warnings are errors.
// Damage in the entropy-coded data often leaves the stream valid to libjpeg
// (Huffman codes resynchronise), so the decoded coefficients are checked too:
// a damaged block typically decodes to one no 8-bit image can have. JPEG
// carries no checksum, so a change that keeps every coefficient possible
// stays undetectable.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace binbow::vision {

// Empty when libjpeg decodes `data` without a warning or an error and every
// coefficient is possible; otherwise libjpeg's message ("Premature end of
// JPEG file", "Corrupt JPEG data: ...") or "Corrupt JPEG data: block X,Y of
// component C decodes to a coefficient no 8-bit image has". Entropy decoding
// only (no inverse DCT or colour conversion), into libjpeg's coefficient
// arrays: 2 bytes per sample of each component, freed before returning.
std::string jpeg_decoding_problem(const std::uint8_t* data, std::size_t size);

struct DecodedJpeg {
  // 8-bit grey or BGR; empty when `problem` is set, and for the CMYK and
  // YCCK JPEGs that this decoder leaves to OpenCV (checked, problem empty).
  cv::Mat image;
  // The image's size when decoded whole (as oriented), which `image` has
  // unless max_width let libjpeg decode it smaller.
  cv::Size full_size;
  std::string problem;  // as jpeg_decoding_problem's
};

// Decodes `data` to 8-bit grey (libjpeg's luminance: the same pixels as
// cv::imread's IMREAD_GRAYSCALE) or BGR (as IMREAD_COLOR), turned as its
// Exif orientation says (as cv::imread does), with jpeg_decoding_problem's
// checks. A single-scan (baseline) JPEG is decoded and checked in one pass; a
// progressive one is checked first, then decoded. With `max_width` > 0,
// libjpeg scales the image down in its inverse DCT by 2, 4 or 8, as far as
// it stays at least twice max_width wide (much faster than decoding it whole;
// the caller resizes the rest of the way). Reuses one libjpeg decompressor per thread. The caller
// bounds the image size from the header first.
DecodedJpeg decode_jpeg(const std::uint8_t* data, std::size_t size, bool grey, int max_width = 0);

// The Exif orientation (1-8, TIFF's tag 274) of a JPEG's first APP1 Exif
// segment; 1 (as stored) when there is none or it is malformed.
int jpeg_exif_orientation(const std::uint8_t* data, std::size_t size);

}  // namespace binbow::vision
