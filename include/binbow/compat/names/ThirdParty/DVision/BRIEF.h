// The include name "ThirdParty/DVision/BRIEF.h" of VINS-Mono/Fusion's copy
// of DLib's DVision: DVision::BRIEF, the BRIEF extractor VINS computes its
// descriptors with, written for binbow with DLib's API and DLib's tests, so
// that its descriptors are bit-identical to DLib's and VINS's for the same
// image, keypoints and test pairs (VINS imports its pairs from a pattern
// file with importPairs). Header-only; needs Boost's dynamic_bitset and
// OpenCV's imgproc, as VINS does. Found through the opt-in target
// binbow::dbow2_names (pkg-config binbow-dbow2-names).
#ifndef BINBOW_COMPAT_NAMES_VINS_DVISION_BRIEF_H
#define BINBOW_COMPAT_NAMES_VINS_DVISION_BRIEF_H

#include <boost/dynamic_bitset.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <vector>

namespace DVision {

/// BRIEF descriptors: bit i is set when the (smoothed) image is darker at
/// the keypoint + (x1[i], y1[i]) than at the keypoint + (x2[i], y2[i]), both
/// rounded toward zero; a test with a point outside the image is 0.
class BRIEF {
 public:
  /// One descriptor; FBrief's vocabulary and database take vectors of them.
  typedef boost::dynamic_bitset<> bitset;

  /// How the constructor draws test pairs.
  enum Type {
    RANDOM,       // both points Gaussian around the keypoint (Calonder's)
    RANDOM_CLOSE  // the second point Gaussian around the first (DLib's default)
  };

  /// Draws `nbits` random test pairs inside a `patch_size` square. The
  /// pairs are random as DLib's are (Gaussian, sigma 0.2 * patch_size for
  /// the first point and 0.08 * patch_size around it for the second, for
  /// RANDOM_CLOSE), not DLib's own draw: to match existing descriptors or a
  /// vocabulary, import the pairs they were made with (importPairs).
  BRIEF(int nbits = 256, int patch_size = 48, Type type = RANDOM_CLOSE)
      : m_bit_length(nbits), m_patch_size(patch_size), m_type(type) {
    if (nbits <= 0 || patch_size <= 1)
      throw std::invalid_argument("DVision::BRIEF needs nbits > 0 and patch_size > 1");
    generateTestPoints();
  }
  virtual ~BRIEF() {}

  int getDescriptorLengthInBits() const { return m_bit_length; }
  Type getType() const { return m_type; }
  int getPatchSize() const { return m_patch_size; }

  void operator()(const cv::Mat& image, const std::vector<cv::KeyPoint>& points,
                  std::vector<bitset>& descriptors, bool treat_image = true) const {
    compute(image, points, descriptors, treat_image);
  }

  /// One descriptor per keypoint, as DLib computes them. With `treat_image`,
  /// the image is first converted to grey (3 channels, taken as RGB) and
  /// smoothed by a 9x9 Gaussian of sigma 2 (cv::GaussianBlur's default
  /// borders); without, it must already be one channel of CV_8U. Throws
  /// std::invalid_argument for other images. (DLib converts only images of
  /// depth 3, CV_16S, and reads anything else as CV_8UC1.)
  void compute(const cv::Mat& image, const std::vector<cv::KeyPoint>& points,
               std::vector<bitset>& descriptors, bool treat_image = true) const {
    // A new matrix for the smoothed image: GaussianBlur into a header of
    // `image` would overwrite the caller's pixels.
    cv::Mat im;
    if (treat_image) {
      cv::Mat grey = image;
      if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_RGB2GRAY);
      cv::GaussianBlur(grey, im, cv::Size(9, 9), 2, 2);
    } else {
      im = image;
    }
    if (im.type() != CV_8UC1) throw std::invalid_argument("DVision::BRIEF needs a CV_8UC1 image");
    descriptors.resize(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      bitset& d = descriptors[k];
      d.resize(static_cast<std::size_t>(m_bit_length));
      d.reset();
      const cv::Point2f& p = points[k].pt;
      for (std::size_t i = 0; i < m_x1.size() && i < d.size(); ++i) {
        // Float sums truncated to int, as DLib does (so -0.5 is column 0).
        const int x1 = static_cast<int>(p.x + m_x1[i]), y1 = static_cast<int>(p.y + m_y1[i]);
        const int x2 = static_cast<int>(p.x + m_x2[i]), y2 = static_cast<int>(p.y + m_y2[i]);
        if (inside(im, x1, y1) && inside(im, x2, y2) &&
            im.ptr<unsigned char>(y1)[x1] < im.ptr<unsigned char>(y2)[x2])
          d.set(i);
      }
    }
  }

  /// The test pairs: test i compares (x1[i], y1[i]) with (x2[i], y2[i]).
  void exportPairs(std::vector<int>& x1, std::vector<int>& y1, std::vector<int>& x2,
                   std::vector<int>& y2) const {
    x1 = m_x1;
    y1 = m_y1;
    x2 = m_x2;
    y2 = m_y2;
  }
  /// Replaces the test pairs; the descriptors become x1.size() bits long.
  /// Throws std::invalid_argument for lists of different lengths.
  void importPairs(const std::vector<int>& x1, const std::vector<int>& y1,
                   const std::vector<int>& x2, const std::vector<int>& y2) {
    if (y1.size() != x1.size() || x2.size() != x1.size() || y2.size() != x1.size())
      throw std::invalid_argument("DVision::BRIEF::importPairs needs four lists of one length");
    m_x1 = x1;
    m_y1 = y1;
    m_x2 = x2;
    m_y2 = y2;
    m_bit_length = static_cast<int>(x1.size());
  }

  /// Hamming distance.
  static int distance(const bitset& a, const bitset& b) {
    return static_cast<int>((a ^ b).count());
  }

 protected:
  void generateTestPoints() {
    // One generator for the program, seeded once, as DLib's is.
    static std::mt19937 generator{std::random_device{}()};
    const float sigma1 = 0.2f * static_cast<float>(m_patch_size);
    const float sigma2 = m_type == RANDOM ? sigma1 : 0.08f * static_cast<float>(m_patch_size);
    const int max_v = m_patch_size / 2;
    // A Gaussian value truncated to int, drawn again until within max_v.
    struct Draw {
      std::mt19937& generator;
      int max_v;
      int operator()(float mean, float sigma) const {
        std::normal_distribution<float> gaussian(mean, sigma);
        for (;;) {
          const int v = static_cast<int>(gaussian(generator));
          if (v >= -max_v && v <= max_v) return v;
        }
      }
    } draw = {generator, max_v};
    const std::size_t n = static_cast<std::size_t>(m_bit_length);
    m_x1.resize(n);
    m_y1.resize(n);
    m_x2.resize(n);
    m_y2.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      m_x1[i] = draw(0.f, sigma1);
      m_y1[i] = draw(0.f, sigma1);
      m_x2[i] = draw(m_type == RANDOM ? 0.f : static_cast<float>(m_x1[i]), sigma2);
      m_y2[i] = draw(m_type == RANDOM ? 0.f : static_cast<float>(m_y1[i]), sigma2);
    }
  }

  static bool inside(const cv::Mat& im, int x, int y) {
    return x >= 0 && x < im.cols && y >= 0 && y < im.rows;
  }

  int m_bit_length;
  int m_patch_size;
  Type m_type;
  std::vector<int> m_x1, m_x2;
  std::vector<int> m_y1, m_y2;
};

}  // namespace DVision

#endif
