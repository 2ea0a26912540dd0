// OpenCV 4.6 decodes a damaged JPEG (cut short, corrupt entropy data) into a
// partly grey image and leaves only libjpeg's warning on stderr. Before
// OpenCV decodes a JPEG, libjpeg reads it once more here, with warnings
// turned into errors.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace binbow::vision {

// Empty when libjpeg decodes `data` without a warning or an error; otherwise
// libjpeg's message ("Premature end of JPEG file", "Corrupt JPEG data: ...").
// Decodes at 1/8 scale: every entropy-coded bit is still read, the inverse
// DCT and colour conversion are nearly free.
std::string jpeg_decoding_problem(const std::uint8_t* data, std::size_t size);

}  // namespace binbow::vision
