// DBoW2 compatibility layer: ORB descriptors (DBoW2's FORB).
//
// C++11; includes the standard library and OpenCV core only (see DBoW2.h).
#ifndef BINBOW_COMPAT_DBOW2_FORB_H
#define BINBOW_COMPAT_DBOW2_FORB_H

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace DBoW2 {

/// Functions on ORB descriptors: a descriptor is a cv::Mat of one row of
/// FORB::L = 32 bytes, type CV_8U (one row of what cv::ORB computes).
class FORB {
 public:
  typedef cv::Mat TDescriptor;
  typedef const TDescriptor* pDescriptor;
  /// Descriptor length in bytes.
  static const int L = 32;

  /// Bitwise majority of the descriptors (a bit is set when at least half of
  /// them, rounded up, have it); an empty Mat for no descriptors.
  static void meanValue(const std::vector<pDescriptor>& descriptors, TDescriptor& mean);
  /// Hamming distance in bits.
  static double distance(const TDescriptor& a, const TDescriptor& b);
  /// The bytes as decimal numbers, each followed by a space (DBoW2's YAML).
  static std::string toString(const TDescriptor& a);
  /// Parses toString()'s form into a 1 x 32 CV_8U Mat.
  static void fromString(TDescriptor& a, const std::string& s);
  /// One row of 256 floats (0 or 1, most significant bit of each byte
  /// first) per descriptor; an empty Mat for no descriptors.
  static void toMat32F(const std::vector<TDescriptor>& descriptors, cv::Mat& mat);
  /// The byte values converted to CV_32F.
  static void toMat32F(const cv::Mat& descriptors, cv::Mat& mat);
  /// The descriptors as the rows of one N x 32 CV_8U Mat.
  static void toMat8U(const std::vector<TDescriptor>& descriptors, cv::Mat& mat);
};

namespace binbow_detail {
// DBoW2 YAML files hold decimal bytes for every descriptor class but FBrief,
// whose words are bit strings (see FBrief.h).
template <class F>
inline bool yaml_bit_strings(const F*) {
  return false;
}
}  // namespace binbow_detail

}  // namespace DBoW2

#endif
