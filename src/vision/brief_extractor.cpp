// The paper's BRIEF extractor; see BriefOptions in binbow/vision/features.h for
// the exact compatibility contract with DLoopDetector's DVision::BRIEF.
#include <algorithm>
#include <cstdint>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "binbow/error.h"
#include "binbow/vision/features.h"
#include "vision/brief_pattern.h"
#include "vision/check_image.h"

namespace binbow::vision {
namespace {

// DVision::BRIEF smooths with this kernel before the tests.
const cv::Size kSmoothingKernel(9, 9);
constexpr double kSmoothingSigma = 2.0;
// Peak memory per pixel of extract(), measured on 1, 4 and 16 MP images
// (docs/limits.md): the smoothed copy, and FAST's corners on textured images.
constexpr double kBytesPerPixel = 1;

class BriefExtractor final : public FeatureExtractor {
 public:
  BriefExtractor(const BriefOptions& options, BriefPattern pattern)
      : options_(options),
        pattern_(std::move(pattern)),
        radius_(pattern_.radius()),
        extent_(pattern_.extent()) {
    if (options_.fast_threshold < 0 || options_.fast_threshold > 255) {
      throw InvalidArgument("BRIEF fast_threshold must be in [0, 255], got " +
                            std::to_string(options_.fast_threshold));
    }
  }

  Features extract(const cv::Mat& image) const override {
    check_grey_image(image, "BRIEF");
    Features features;
    features.descriptors = DescriptorMatrix(code_size());
    if (image.empty()) return features;

    std::vector<cv::KeyPoint> corners;
    cv::FAST(image, corners, options_.fast_threshold, options_.non_max_suppression);
    const std::vector<cv::KeyPoint> kept = strongest_described(corners, image.size());
    if (kept.empty()) return features;

    const cv::Mat smoothed = smooth(image);
    features.keypoints.reserve(kept.size());
    features.descriptors.resize(kept.size());
    describe(smoothed, kept, features.descriptors);
    for (const cv::KeyPoint& corner : kept) {
      Keypoint keypoint;
      keypoint.x = corner.pt.x;
      keypoint.y = corner.pt.y;
      keypoint.size = static_cast<float>(2 * radius_);  // 48 for the default pattern
      keypoint.angle = -1;
      keypoint.response = corner.response;
      keypoint.octave = 0;
      features.keypoints.push_back(keypoint);
    }
    return features;
  }

  std::size_t code_size() const override { return pattern_.tests() / 8; }
  std::string name() const override { return "brief"; }
  double bytes_per_pixel() const override { return kBytesPerPixel; }

 private:
  // Every test of a keypoint at (x, y) lies inside the image (the pattern's
  // extent on each side, not its radius: DLoopDetector's y runs from −23 to +24).
  bool tests_inside(int x, int y, cv::Size size) const {
    return x + extent_.min_x >= 0 && y + extent_.min_y >= 0 && x + extent_.max_x < size.width &&
           y + extent_.max_y < size.height;
  }

  // The corners described (all with keep_border_corners, else those whose
  // every test lies inside the image), the strongest first (stable, so equal
  // responses keep FAST's raster order), at most max_features.
  std::vector<cv::KeyPoint> strongest_described(const std::vector<cv::KeyPoint>& corners,
                                                cv::Size size) const {
    std::vector<cv::KeyPoint> inside;
    inside.reserve(corners.size());
    for (const cv::KeyPoint& corner : corners) {
      if (options_.keep_border_corners ||
          tests_inside(static_cast<int>(corner.pt.x), static_cast<int>(corner.pt.y), size)) {
        inside.push_back(corner);
      }
    }
    const auto stronger = [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
      return a.response > b.response;
    };
    std::stable_sort(inside.begin(), inside.end(), stronger);
    if (options_.max_features > 0 &&
        inside.size() > static_cast<std::size_t>(options_.max_features)) {
      inside.resize(static_cast<std::size_t>(options_.max_features));
    }
    return inside;
  }

  // The whole image is smoothed, as DVision does: cv::GaussianBlur on a region
  // of interest takes another code path whose rounding differs by one grey
  // level on ~1% of the pixels, which would flip bits.
  // A region-of-interest input is copied first for the same reason.
  static cv::Mat smooth(const cv::Mat& image) {
    const cv::Mat whole = image.isSubmatrix() ? image.clone() : image;
    cv::Mat smoothed;
    cv::GaussianBlur(whole, smoothed, kSmoothingKernel, kSmoothingSigma, kSmoothingSigma,
                     cv::BORDER_REFLECT_101);
    return smoothed;
  }

  void describe(const cv::Mat& smoothed, const std::vector<cv::KeyPoint>& keypoints,
                DescriptorMatrix& descriptors) const {
    const std::size_t tests = pattern_.tests();
    const auto step = static_cast<std::ptrdiff_t>(smoothed.step1());
    std::vector<std::ptrdiff_t> first(tests), second(tests);
    for (std::size_t i = 0; i < tests; ++i) {
      first[i] = pattern_.y1[i] * step + pattern_.x1[i];
      second[i] = pattern_.y2[i] * step + pattern_.x2[i];
    }
    for (std::size_t k = 0; k < keypoints.size(); ++k) {
      const int x = static_cast<int>(keypoints[k].pt.x), y = static_cast<int>(keypoints[k].pt.y);
      std::uint8_t* out = descriptors.row(k);
      if (!tests_inside(x, y, smoothed.size())) {
        describe_at_border(smoothed, x, y, out);
        continue;
      }
      const std::uint8_t* center = smoothed.ptr<std::uint8_t>(y) + x;
      for (std::size_t byte = 0; byte < tests / 8; ++byte) {
        unsigned value = 0;
        for (unsigned bit = 0; bit < 8; ++bit) {
          const std::size_t test = byte * 8 + bit;
          value |= static_cast<unsigned>(center[first[test]] < center[second[test]]) << bit;
        }
        out[byte] = static_cast<std::uint8_t>(value);
      }
    }
  }

  // A keypoint whose pattern reaches past the border: a test with a point
  // outside the image is a 0 bit, as in DVision::BRIEF.
  void describe_at_border(const cv::Mat& smoothed, int x, int y, std::uint8_t* out) const {
    const auto inside = [&smoothed](int px, int py) {
      return px >= 0 && py >= 0 && px < smoothed.cols && py < smoothed.rows;
    };
    for (std::size_t byte = 0; byte < pattern_.tests() / 8; ++byte) {
      unsigned value = 0;
      for (unsigned bit = 0; bit < 8; ++bit) {
        const std::size_t test = byte * 8 + bit;
        const int ax = x + pattern_.x1[test], ay = y + pattern_.y1[test];
        const int bx = x + pattern_.x2[test], by = y + pattern_.y2[test];
        if (inside(ax, ay) && inside(bx, by) &&
            smoothed.at<std::uint8_t>(ay, ax) < smoothed.at<std::uint8_t>(by, bx))
          value |= 1u << bit;
      }
      out[byte] = static_cast<std::uint8_t>(value);
    }
  }

  BriefOptions options_;
  BriefPattern pattern_;
  int radius_;
  BriefPattern::Extent extent_;
};

}  // namespace

std::unique_ptr<FeatureExtractor> make_brief_extractor(const BriefOptions& options) {
  BriefPattern pattern = options.pattern_file.empty() ? default_brief_pattern()
                                                      : load_brief_pattern(options.pattern_file);
  return std::make_unique<BriefExtractor>(options, std::move(pattern));
}

}  // namespace binbow::vision
