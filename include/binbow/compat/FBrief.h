// DBoW2 compatibility layer: BRIEF descriptors (DBoW2's FBrief).
//
// C++11; includes the standard library and OpenCV core only (see DBoW2.h).
#ifndef BINBOW_COMPAT_DBOW2_FBRIEF_H
#define BINBOW_COMPAT_DBOW2_FBRIEF_H

#include <bitset>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace DBoW2 {

/// Functions on BRIEF descriptors, as DBoW2 declares them: a descriptor is a
/// std::bitset<256> (DLib's BRIEF256::bitset), bit i holding test i.
///
/// The vocabulary and database templates also take the same descriptors as
/// boost::dynamic_bitset<> (DLib's and VINS's DVision::BRIEF::bitset) or as
/// cv::Mat rows of 32 CV_8U bytes with test i in bit i % 8 (least
/// significant first) of byte i / 8, and give the same words for the same
/// bits: that is the order of DBoW2's YAML bit strings and of VINS's binary
/// vocabularies.
class FBrief {
 public:
  /// Descriptor length in bits.
  static const int L = 256;
  typedef std::bitset<L> TDescriptor;
  typedef const TDescriptor* pDescriptor;

  /// Bitwise majority: a bit is set when more than half of the descriptors
  /// have it (DBoW2's rule); all zeros for no descriptors.
  static void meanValue(const std::vector<pDescriptor>& descriptors, TDescriptor& mean);
  /// Hamming distance in bits.
  static double distance(const TDescriptor& a, const TDescriptor& b);
  /// The 256 bits as '0'/'1', bit 255 first (bitset::to_string, the form of
  /// DBoW2's YAML files).
  static std::string toString(const TDescriptor& a);
  /// Parses toString()'s form; throws std::invalid_argument for anything but
  /// 256 characters '0' or '1' (where DBoW2 reads what it can).
  static void fromString(TDescriptor& a, const std::string& s);
  /// One row of 256 floats (0 or 1, bit 0 first) per descriptor; an empty
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
