// Feature extraction: keypoints and binary descriptors from grey images.
//
// Descriptor layout (all extractors): bit i of a descriptor is bit (i % 8),
// counted from the least significant bit, of byte (i / 8) — the layout of
// descriptors.h and of OpenCV's binary descriptors.
//
// BRIEF and DBoW2/DLoopDetector compatibility: bit i is the outcome of test i
// of the pattern (x1[i], y1[i], x2[i], y2[i]): 1 when the smoothed intensity
// at (x1, y1) is lower than at (x2, y2), as in DVision::BRIEF, whose
// boost::dynamic_bitset / std::bitset<256> has bit i = test i. DBoW2 (FBrief)
// writes such a bitset as the 0/1 string of bitset::to_string(), most
// significant bit first: character k of a 256-character string is bit 255 - k.
// A DBoW2 YAML BRIEF descriptor string s therefore maps to our bytes as
//   bit i = (s[s.size() - 1 - i] == '1'),  i.e. byte i / 8 |= bit << (i % 8).
// With that mapping, vocabularies trained with DLoopDetector, VINS-Mono or
// VINS-Fusion (brief_k10L6, brief_lite.voc.gz) describe our BRIEF descriptors.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "binbow/descriptors.h"

namespace binbow::vision {

struct Keypoint {
  float x = 0, y = 0;  // pixel coordinates in the input image
  float size = 0;      // diameter of the described region, pixels
  float angle = -1;    // degrees, -1 when not oriented (BRIEF)
  float response = 0;  // detector score
  int octave = 0;      // pyramid level
};

// Keypoints and their descriptors: descriptors.row(i) describes keypoints[i].
// An image without usable corners gives no keypoints and an empty matrix whose
// code_size() is still the extractor's.
struct Features {
  std::vector<Keypoint> keypoints;
  DescriptorMatrix descriptors;
};

// The memory one extraction may take by default: what sets each extractor's
// pixel limit (FeatureExtractor::max_pixels). AKAZE's nonlinear scale space
// takes about 110 bytes per pixel, so a 100-megapixel image would need 11 GB.
inline constexpr std::uint64_t kDefaultExtractionMemoryBytes = std::uint64_t{2} << 30;

// Extractors are immutable after construction: extract() may be called from
// several threads at once.
class FeatureExtractor {
 public:
  virtual ~FeatureExtractor() = default;
  // Peak memory extract() takes per pixel of the image, in bytes, measured on
  // 1, 4 and 16 MP images (docs/limits.md): ORB 4, BRIEF 1, BRISK 6, AKAZE
  // 120. 0 when not known (an extractor built elsewhere).
  virtual double bytes_per_pixel() const { return 0; }
  // The most pixels extract() should be given for its memory to stay within
  // `memory_bytes`: memory_bytes / bytes_per_pixel(), UINT64_MAX when that is
  // not known. extract() itself does not refuse larger images (the caller
  // chose them); ImageSource refuses such files before decoding them when
  // told the limit (ImageSourceOptions::max_extracted_pixels).
  std::uint64_t max_pixels(std::uint64_t memory_bytes = kDefaultExtractionMemoryBytes) const;
  // `image` is 8-bit grey (CV_8UC1); throws InvalidArgument otherwise. An
  // empty (0×0) image, one without corners, or (OpenCV-backed extractors) one
  // smaller than 16×16 gives empty Features, not an error.
  virtual Features extract(const cv::Mat& image) const = 0;
  // Bytes per descriptor (32 for ORB and BRIEF-256).
  virtual std::size_t code_size() const = 0;
  virtual std::string name() const = 0;  // "orb", "brief", "akaze", "brisk", ...
};

// extractor.extract(image) for the image read from `file` (a path, or
// "video.mp4#123" for a video frame): every failure, running out of memory
// included, is a FileError naming `file`, so that a run over thousands of
// images says which one it could not take.
Features extract_features(const FeatureExtractor& extractor, const cv::Mat& image,
                          const std::string& file);

// OpenCV's ORB (oriented FAST + rotated BRIEF, 32 bytes) on a scale pyramid.
struct OrbOptions {
  int max_features = 1000;
  float scale_factor = 1.2f;  // between pyramid levels
  int levels = 8;             // pyramid levels
  int fast_threshold = 20;
  int edge_threshold = 31;  // border in pixels where no keypoint is detected
};

// The paper's BRIEF, bit for bit DLoopDetector's (DVision::BRIEF with its
// demo's FAST detection): FAST-9 corners on the raw image (threshold,
// optional non-maximum suppression), the `max_features` strongest kept by
// FAST score and returned strongest first (ties: raster order); no
// orientation, no scale; Keypoint::size is the patch side (48). The image is
// smoothed with cv::GaussianBlur (9×9, sigma 2, reflect-101 border) and each
// test compares two smoothed pixels at integer offsets from the keypoint.
// Keypoints whose tests would leave the image are dropped (DVision keeps them
// and leaves those bits 0) before the strongest are chosen, so every returned
// descriptor is identical to DVision's for the same keypoint and the same
// OpenCV (the smoothing's fixed-point rounding is OpenCV's). Defaults follow
// the paper (threshold 10, 300 corners); DLoopDetector's demo uses threshold
// 20 and every corner (max_features 0).
struct BriefOptions {
  int max_features = 300;  // the strongest FAST corners by response; ≤ 0: all
  int fast_threshold = 10;
  bool non_max_suppression = true;
  // OpenCV YAML/XML with integer sequences x1 y1 x2 y2 (one test each, a
  // multiple of 8 tests, offsets within ±64 pixels; a regular file, gzip
  // allowed, at most 4 MiB before and after decompression, nested at most 64
  // levels); empty: the built-in pattern, which is DLoopDetector's/VINS'
  // brief_pattern.yml (256 tests, 48×48).
  std::string pattern_file;
  // Corners whose pattern reaches past the image border are described too,
  // each test with a point outside the image giving a 0 bit (DLib's
  // DVision::BRIEF, which DLoopDetector uses, does this). false: only corners
  // whose every test lies inside the image.
  bool keep_border_corners = false;
};

std::unique_ptr<FeatureExtractor> make_orb_extractor(const OrbOptions& options = {});
// Throws FileError naming the pattern file when it cannot be read or is invalid.
std::unique_ptr<FeatureExtractor> make_brief_extractor(const BriefOptions& options = {});
// Any OpenCV binary-descriptor Feature2D (AKAZE with MLDB: 61 bytes, BRISK: 64
// bytes, ORB, ...) whose descriptors are CV_8U rows; `name` is what name()
// returns; `max_features` > 0 keeps the strongest keypoints by response before
// describing them; `bytes_per_pixel` is what bytes_per_pixel() returns (0: not
// known). Calls to the shared cv::Feature2D are serialised by a mutex,
// as OpenCV does not promise that it is thread-safe. Throws InvalidArgument
// for a null detector or one whose descriptors are not bytes.
std::unique_ptr<FeatureExtractor> make_opencv_extractor(cv::Ptr<cv::Feature2D> detector,
                                                        std::string name, int max_features = 0,
                                                        double bytes_per_pixel = 0);
// "orb", "brief", "akaze" or "brisk" with default options except the number
// of features (≤ 0: the extractor's default; AKAZE and BRISK keep the
// strongest `max_features` when > 0). Throws InvalidArgument for other names.
std::unique_ptr<FeatureExtractor> make_extractor(const std::string& name, int max_features = 0);
// The extractor binbow's tools run when none is named.
inline constexpr const char* kDefaultDescriptor = "orb";
// The names make_extractor() accepts, ORB first: the one list that tools
// offer as choices.
std::vector<std::string> extractor_names();

// Conversions from and to OpenCV's keypoints; `descriptors` must be CV_8U with
// one row per keypoint (throws InvalidArgument otherwise); an empty Mat gives
// empty Features of code size `empty_code_size`.
Features features_from_opencv(const std::vector<cv::KeyPoint>& keypoints,
                              const cv::Mat& descriptors, std::size_t empty_code_size);
std::vector<cv::KeyPoint> to_opencv(const std::vector<Keypoint>& keypoints);

}  // namespace binbow::vision
