// DBoW2 compatibility layer: BRIEF descriptors (DBoW2's FBrief).
//
// C++11; includes the standard library and OpenCV core only (see DBoW2.h).
#ifndef BINBOW_COMPAT_DBOW2_FBRIEF_H
#define BINBOW_COMPAT_DBOW2_FBRIEF_H

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace DBoW2 {

/// Functions on BRIEF descriptors. A descriptor is a cv::Mat of one row of
/// 32 CV_8U bytes, as FORB's and as binbow's BRIEF extractor produces: test i
/// of the 256-test string is bit i % 8 (least significant first) of byte
/// i / 8. That is the bit order of DLoopDetector's and VINS's bitsets, of
/// DBoW2's YAML bit strings and of VINS's binary vocabularies, so a
/// vocabulary read from any of them gives their words. (DBoW2 itself keeps
/// BRIEF descriptors in a boost::dynamic_bitset: code that builds them bit by
/// bit sets bit i % 8 of byte i / 8 instead of bit i.)
class FBrief {
 public:
  typedef cv::Mat TDescriptor;
  typedef const TDescriptor* pDescriptor;
  /// Descriptor length in bits.
  static const int L = 256;

  /// Bitwise majority (a bit is set when more than half of the descriptors
  /// have it, as DBoW2's FBrief); an empty Mat for no descriptors.
  static void meanValue(const std::vector<pDescriptor>& descriptors, TDescriptor& mean);
  /// Hamming distance in bits.
  static double distance(const TDescriptor& a, const TDescriptor& b);
  /// The 256 tests as '0'/'1', test 255 first (DBoW2's bitset::to_string,
  /// the form of its YAML files).
  static std::string toString(const TDescriptor& a);
  /// Parses toString()'s form into a 1 x 32 CV_8U Mat; throws
  /// std::invalid_argument for anything else.
  static void fromString(TDescriptor& a, const std::string& s);
  /// One row of 256 floats (0 or 1, test 0 first) per descriptor; an empty
  /// Mat for no descriptors.
  static void toMat32F(const std::vector<TDescriptor>& descriptors, cv::Mat& mat);
};

namespace binbow_detail {
inline bool yaml_bit_strings(const FBrief*) {
  return true;
}
}  // namespace binbow_detail

}  // namespace DBoW2

#endif
