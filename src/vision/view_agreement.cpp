#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "binbow/descriptors.h"
#include "binbow/error.h"
#include "binbow/vision/geometric_check.h"

namespace binbow::vision {
namespace {

// RANSAC threshold of the homography of the inliers, pixels (point to point).
constexpr double kHomographyTolerance = 3.0;

// The finite keypoints of one image sorted by x, so that the features near a
// point are found by a binary search, whatever the coordinates (a grid sized
// by their extent would let one stray coordinate decide its memory).
class KeypointIndex {
 public:
  explicit KeypointIndex(Span<Keypoint> keypoints) : keypoints_(keypoints) {
    for (std::size_t i = 0; i < keypoints.size(); ++i)
      if (std::isfinite(keypoints[i].x) && std::isfinite(keypoints[i].y))
        by_x_.push_back(static_cast<std::uint32_t>(i));
    std::sort(by_x_.begin(), by_x_.end(),
              [&](std::uint32_t a, std::uint32_t b) { return keypoints[a].x < keypoints[b].x; });
    for (const std::uint32_t i : by_x_) {
      min_y_ = std::min(min_y_, static_cast<double>(keypoints[i].y));
      max_y_ = std::max(max_y_, static_cast<double>(keypoints[i].y));
    }
  }

  // Whether (x, y) lies within the keypoints' bounding box (false for
  // non-finite coordinates).
  bool covers(double x, double y) const {
    return !by_x_.empty() && x >= keypoints_[by_x_.front()].x && x <= keypoints_[by_x_.back()].x &&
           y >= min_y_ && y <= max_y_;
  }

  // Calls visit(i) for every keypoint within kReappearanceRadius of (x, y).
  template <typename Visit>
  void near(double x, double y, Visit visit) const {
    auto it =
        std::lower_bound(by_x_.begin(), by_x_.end(), x - kReappearanceRadius,
                         [&](std::uint32_t i, double value) { return keypoints_[i].x < value; });
    // Squared distances: this runs for every feature of every loop, and std::hypot is slow.
    constexpr double r2 = kReappearanceRadius * kReappearanceRadius;
    for (; it != by_x_.end() && keypoints_[*it].x <= x + kReappearanceRadius; ++it) {
      const double dx = keypoints_[*it].x - x, dy = keypoints_[*it].y - y;
      if (dx * dx + dy * dy <= r2) visit(*it);
    }
  }

 private:
  Span<Keypoint> keypoints_;
  std::vector<std::uint32_t> by_x_;
  double min_y_ = std::numeric_limits<double>::infinity();
  double max_y_ = -std::numeric_limits<double>::infinity();
};

// The share of `from`'s features that `mapping` puts within `to`'s extent
// and that find a similar feature of `to` there.
double reappearing_share(Span<Keypoint> from, const DescriptorView& from_descriptors,
                         const KeypointIndex& to, const DescriptorView& to_descriptors,
                         const cv::Matx33d& mapping) {
  const auto max_bits = static_cast<std::uint32_t>(kReappearanceBits * 8.0 *
                                                   static_cast<double>(to_descriptors.code_size));
  std::size_t landing = 0, reappearing = 0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const cv::Vec3d mapped = mapping * cv::Vec3d(from[i].x, from[i].y, 1);
    if (!(std::abs(mapped[2]) > 1e-12)) continue;
    const double x = mapped[0] / mapped[2], y = mapped[1] / mapped[2];
    if (!to.covers(x, y)) continue;
    ++landing;
    bool found = false;
    to.near(x, y, [&](std::uint32_t j) {
      found = found || hamming_distance(from_descriptors.row(i), to_descriptors.row(j),
                                        to_descriptors.code_size) <= max_bits;
    });
    reappearing += found;
  }
  return landing > 0 ? static_cast<double>(reappearing) / static_cast<double>(landing) : 0.0;
}

}  // namespace

double view_agreement(Span<Keypoint> first, const DescriptorView& first_descriptors,
                      Span<Keypoint> second, const DescriptorView& second_descriptors,
                      const std::vector<Correspondence>& inliers) {
  if (first.size() != first_descriptors.rows || second.size() != second_descriptors.rows ||
      first_descriptors.code_size != second_descriptors.code_size)
    throw InvalidArgument(
        "view_agreement: keypoints and descriptors of the two images do not agree");
  const std::size_t points = distinct_inliers(first, second, inliers);
  if (points < 4) return 0;
  std::vector<cv::Point2d> p, q;
  for (const Correspondence& c : inliers) {
    const Keypoint &a = first[c.first], &b = second[c.second];
    if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y))
      return 0;
    p.emplace_back(a.x, a.y);
    q.emplace_back(b.x, b.y);
  }
  const cv::Mat found = cv::findHomography(p, q, cv::RANSAC, kHomographyTolerance);
  if (found.rows != 3 || found.cols != 3) return 0;
  cv::Matx33d homography;
  found.convertTo(cv::Mat(3, 3, CV_64F, homography.val), CV_64F);
  bool invertible = false;
  const cv::Matx33d inverse = homography.inv(cv::DECOMP_LU, &invertible);
  if (!invertible) return 0;
  const KeypointIndex first_index(first), second_index(second);
  return std::min(
      reappearing_share(first, first_descriptors, second_index, second_descriptors, homography),
      reappearing_share(second, second_descriptors, first_index, first_descriptors, inverse));
}

}  // namespace binbow::vision
