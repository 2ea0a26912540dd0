// Feature extraction: keypoints and binary descriptors from grey images.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "binbow/descriptors.h"

namespace binbow::vision {

struct Keypoint {
  float x = 0, y = 0;     // pixel coordinates in the input image
  float size = 0;         // diameter of the described region, pixels
  float angle = -1;       // degrees, -1 when not oriented (BRIEF)
  float response = 0;     // detector score
  int octave = 0;         // pyramid level
};

// Keypoints and their descriptors: descriptors.row(i) describes keypoints[i].
struct Features {
  std::vector<Keypoint> keypoints;
  DescriptorMatrix descriptors;
};

class FeatureExtractor {
 public:
  virtual ~FeatureExtractor() = default;
  // `image` is 8-bit grey (CV_8UC1); throws InvalidArgument otherwise. An
  // image without corners gives empty Features, not an error.
  virtual Features extract(const cv::Mat& image) const = 0;
  virtual std::size_t code_size() const = 0;
  virtual std::string name() const = 0;  // "orb", "brief"
};

struct OrbOptions {
  int max_features = 1000;
  float scale_factor = 1.2f;
  int levels = 8;
  int fast_threshold = 20;
  int edge_threshold = 31;
};

// The paper's BRIEF: FAST corners (no orientation, no scale), image smoothed
// with a Gaussian, 256 intensity tests in a 48×48 patch, bit and byte layout
// of DLoopDetector's DVision::BRIEF so that DBoW2 BRIEF vocabularies apply.
struct BriefOptions {
  int max_features = 300;       // the strongest FAST corners by response
  int fast_threshold = 10;
  bool non_max_suppression = true;
  std::string pattern_file;     // OpenCV YAML with x1 y1 x2 y2; empty: built-in pattern
};

std::unique_ptr<FeatureExtractor> make_orb_extractor(const OrbOptions& options = {});
std::unique_ptr<FeatureExtractor> make_brief_extractor(const BriefOptions& options = {});
// "orb" or "brief" with default options except the number of features
// (≤ 0: the extractor's default). Throws InvalidArgument for other names.
std::unique_ptr<FeatureExtractor> make_extractor(const std::string& name, int max_features = 0);

}  // namespace binbow::vision
