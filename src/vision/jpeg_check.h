// OpenCV 4.6 decodes a damaged JPEG (cut short, corrupt entropy data) into a
// partly grey image and leaves only libjpeg's warning on stderr. Before
// OpenCV decodes a JPEG, libjpeg reads it once more here, with warnings
// turned into errors. Damage in the entropy-coded data often leaves the
// stream valid to libjpeg (Huffman codes resynchronise), so the decoded
// coefficients are checked too: a damaged block typically decodes to one no
// 8-bit image can have. JPEG carries no checksum, so a change that keeps
// every coefficient possible stays undetectable.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace binbow::vision {

// Empty when libjpeg decodes `data` without a warning or an error and every
// coefficient is possible; otherwise libjpeg's message ("Premature end of
// JPEG file", "Corrupt JPEG data: ...") or "Corrupt JPEG data: block X,Y of
// component C decodes to a coefficient no 8-bit image has". Entropy decoding
// only (no inverse DCT or colour conversion), into libjpeg's coefficient
// arrays: 2 bytes per sample of each component, freed before returning.
std::string jpeg_decoding_problem(const std::uint8_t* data, std::size_t size);

}  // namespace binbow::vision
