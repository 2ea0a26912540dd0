// Feature extractors backed by OpenCV's Feature2D: ORB and any binary descriptor.
#include <limits>
#include <mutex>

#include "binbow/error.h"
#include "binbow/vision/features.h"
#include "vision/check_image.h"

namespace binbow::vision {
namespace {

// OpenCV's detectors assert on very small images (BRISK below 6 pixels, ORB
// and AKAZE at 1 pixel); no detector finds a describable corner below this.
constexpr int kMinimumSide = 16;

bool too_small(const cv::Mat& image) {
  return image.cols < kMinimumSide || image.rows < kMinimumSide;
}

// Peak memory per pixel of extract(), measured (getrusage's peak resident
// memory, above the decoded image) on 1, 4 and 16 MP images and rounded up;
// docs/limits.md has the numbers.
constexpr double kOrbBytesPerPixel = 4;      // 8-level pyramid, Harris scores
constexpr double kAkazeBytesPerPixel = 120;  // about 20 float images of the nonlinear scale space
constexpr double kBriskBytesPerPixel = 6;    // octaves and intra-octaves, AGAST scores

// An OpenCV failure on a valid image becomes a binbow::Error naming the extractor.
[[noreturn]] void rethrow_opencv(const std::string& name, const cv::Exception& e) {
  throw Error(name + ": OpenCV failed: " + e.msg);
}

// ORB builds a fresh cv::ORB per call: creating one costs microseconds, and
// no state is shared between threads.
class OrbExtractor final : public FeatureExtractor {
 public:
  explicit OrbExtractor(const OrbOptions& options) : options_(options) {
    if (options_.max_features <= 0 || options_.levels <= 0 || options_.scale_factor <= 1.f ||
        options_.fast_threshold < 0 || options_.edge_threshold < 0) {
      throw InvalidArgument(
          "ORB options need max_features > 0, levels > 0, scale_factor > 1, "
          "fast_threshold >= 0 and edge_threshold >= 0");
    }
  }

  Features extract(const cv::Mat& image) const override {
    check_grey_image(image, "ORB");
    if (too_small(image)) return features_from_opencv({}, cv::Mat(), code_size());
    const cv::Ptr<cv::ORB> orb =
        cv::ORB::create(options_.max_features, options_.scale_factor, options_.levels,
                        options_.edge_threshold, 0, 2, cv::ORB::HARRIS_SCORE,
                        /*patchSize=*/31, options_.fast_threshold);
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    try {
      orb->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
    } catch (const cv::Exception& e) {
      rethrow_opencv("orb", e);
    }
    return features_from_opencv(keypoints, descriptors, code_size());
  }

  std::size_t code_size() const override { return 32; }
  std::string name() const override { return "orb"; }
  double bytes_per_pixel() const override { return kOrbBytesPerPixel; }

 private:
  OrbOptions options_;
};

class OpenCvExtractor final : public FeatureExtractor {
 public:
  OpenCvExtractor(cv::Ptr<cv::Feature2D> detector, std::string name, int max_features,
                  double bytes_per_pixel)
      : detector_(std::move(detector)),
        name_(std::move(name)),
        max_features_(max_features),
        bytes_per_pixel_(bytes_per_pixel) {
    if (!detector_) throw InvalidArgument("make_opencv_extractor: null cv::Feature2D");
    if (detector_->descriptorType() != CV_8U) {
      throw InvalidArgument("make_opencv_extractor: " + name_ +
                            " does not produce binary (CV_8U) descriptors");
    }
    code_size_ = static_cast<std::size_t>(detector_->descriptorSize());
  }

  Features extract(const cv::Mat& image) const override {
    check_grey_image(image, name_.c_str());
    if (too_small(image)) return features_from_opencv({}, cv::Mat(), code_size_);
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      try {
        detector_->detect(image, keypoints);
        if (max_features_ > 0) cv::KeyPointsFilter::retainBest(keypoints, max_features_);
        if (!keypoints.empty()) detector_->compute(image, keypoints, descriptors);
      } catch (const cv::Exception& e) {
        rethrow_opencv(name_, e);
      }
    }
    if (keypoints.empty()) descriptors.release();
    return features_from_opencv(keypoints, descriptors, code_size_);
  }

  std::size_t code_size() const override { return code_size_; }
  std::string name() const override { return name_; }
  double bytes_per_pixel() const override { return bytes_per_pixel_; }

 private:
  cv::Ptr<cv::Feature2D> detector_;
  std::string name_;
  int max_features_;
  double bytes_per_pixel_;
  std::size_t code_size_ = 0;
  mutable std::mutex mutex_;
};

}  // namespace

std::uint64_t FeatureExtractor::max_pixels(std::uint64_t memory_bytes) const {
  const double per_pixel = bytes_per_pixel();
  if (!(per_pixel > 0)) return std::numeric_limits<std::uint64_t>::max();
  return static_cast<std::uint64_t>(static_cast<double>(memory_bytes) / per_pixel);
}

std::unique_ptr<FeatureExtractor> make_orb_extractor(const OrbOptions& options) {
  return std::make_unique<OrbExtractor>(options);
}

std::unique_ptr<FeatureExtractor> make_opencv_extractor(cv::Ptr<cv::Feature2D> detector,
                                                        std::string name, int max_features,
                                                        double bytes_per_pixel) {
  return std::make_unique<OpenCvExtractor>(std::move(detector), std::move(name), max_features,
                                           bytes_per_pixel);
}

std::unique_ptr<FeatureExtractor> make_extractor(const std::string& name, int max_features) {
  if (name == "orb") {
    OrbOptions options;
    if (max_features > 0) options.max_features = max_features;
    return make_orb_extractor(options);
  }
  if (name == "brief") {
    BriefOptions options;
    if (max_features > 0) options.max_features = max_features;
    return make_brief_extractor(options);
  }
  if (name == "akaze")
    return make_opencv_extractor(cv::AKAZE::create(), "akaze", max_features, kAkazeBytesPerPixel);
  if (name == "brisk")
    return make_opencv_extractor(cv::BRISK::create(), "brisk", max_features, kBriskBytesPerPixel);
  std::string expected;
  for (const std::string& known : extractor_names())
    expected += (expected.empty() ? "" : ", ") + known;
  throw InvalidArgument("unknown feature type '" + name + "'; expected one of " + expected);
}

std::vector<std::string> extractor_names() {
  return {"orb", "brief", "akaze", "brisk"};
}

}  // namespace binbow::vision
