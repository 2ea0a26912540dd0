// DBoW2 compatibility layer: BRIEF descriptors (DBoW2's FBrief).
//
// C++11; includes the standard library and OpenCV core only (see DBoW2.h).
#ifndef BINBOW_COMPAT_DBOW2_FBRIEF_H
#define BINBOW_COMPAT_DBOW2_FBRIEF_H

#include <bitset>
#include <cstddef>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace DBoW2 {

/// Functions on BRIEF descriptors. As in DBoW2, a descriptor is a
/// std::bitset<256> (what DLoopDetector's and VINS's BRIEF extractors
/// produce); bit i is bit i % 8 of byte i / 8 of binbow's descriptor bytes,
/// the layout binbow reads from and writes to DBoW2 YAML files.
class FBrief {
 public:
  /// Descriptor length in bits.
  static const int L = 256;
  typedef std::bitset<L> TDescriptor;
  typedef const TDescriptor* pDescriptor;

  /// Bitwise majority (a bit is set when more than half of the descriptors
  /// have it); all zeros for no descriptors.
  static void meanValue(const std::vector<pDescriptor>& descriptors, TDescriptor& mean);
  /// Hamming distance in bits.
  static double distance(const TDescriptor& a, const TDescriptor& b);
  /// bitset::to_string(): bit 255 first.
  static std::string toString(const TDescriptor& a);
  static void fromString(TDescriptor& a, const std::string& s);
  /// One row of 256 floats (0 or 1, bit 0 first) per descriptor.
  static void toMat32F(const std::vector<TDescriptor>& descriptors, cv::Mat& mat);
};

namespace binbow_detail {
inline void append_descriptor_bytes(const FBrief::TDescriptor& d, std::size_t code_size,
                                    std::vector<unsigned char>& out) {
  if (code_size != 0 && code_size * 8 != static_cast<std::size_t>(FBrief::L))
    throw std::invalid_argument("a 256-bit BRIEF descriptor does not fit a vocabulary of " +
                                std::to_string(code_size * 8) + "-bit words");
  for (std::size_t byte = 0; byte < code_size; ++byte) {
    unsigned char value = 0;
    for (std::size_t bit = 0; bit < 8; ++bit)
      if (d[byte * 8 + bit]) value = static_cast<unsigned char>(value | (1u << bit));
    out.push_back(value);
  }
}

inline void descriptor_from_bytes(const unsigned char* bytes, std::size_t code_size,
                                  FBrief::TDescriptor& d) {
  d.reset();
  for (std::size_t i = 0; i < code_size * 8 && i < d.size(); ++i)
    if ((bytes[i / 8] >> (i % 8)) & 1u) d.set(i);
}

// DBoW2 YAML files of BRIEF vocabularies hold FBrief::toString's bit strings.
inline bool yaml_bit_strings(const FBrief::TDescriptor*) {
  return true;
}
}  // namespace binbow_detail

}  // namespace DBoW2

#endif
