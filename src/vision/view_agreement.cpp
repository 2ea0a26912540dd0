#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>

#include "binbow/descriptors.h"
#include "binbow/error.h"
#include "binbow/vision/geometric_check.h"

namespace binbow::vision {
namespace {

// RANSAC threshold of the homography of the inliers, pixels (point to point).
constexpr double kHomographyTolerance = 3.0;

// Keypoints of one image bucketed in square cells of kReappearanceRadius, so
// that the features near a point are found without visiting every feature.
class KeypointGrid {
 public:
  explicit KeypointGrid(Span<Keypoint> keypoints) : keypoints_(keypoints) {
    min_x_ = max_x_ = keypoints[0].x;
    min_y_ = max_y_ = keypoints[0].y;
    for (const Keypoint& k : keypoints) {
      min_x_ = std::min(min_x_, k.x);
      max_x_ = std::max(max_x_, k.x);
      min_y_ = std::min(min_y_, k.y);
      max_y_ = std::max(max_y_, k.y);
    }
    columns_ = cell(max_x_ - min_x_) + 1;
    rows_ = cell(max_y_ - min_y_) + 1;
    cells_.resize(static_cast<std::size_t>(columns_) * static_cast<std::size_t>(rows_));
    for (std::size_t i = 0; i < keypoints.size(); ++i)
      cells_[static_cast<std::size_t>(cell(keypoints[i].y - min_y_)) * columns_ +
             static_cast<std::size_t>(cell(keypoints[i].x - min_x_))]
          .push_back(static_cast<std::uint32_t>(i));
  }

  bool covers(double x, double y) const {
    return x >= min_x_ && x <= max_x_ && y >= min_y_ && y <= max_y_;
  }

  // Calls visit(i) for every keypoint within kReappearanceRadius of (x, y).
  template <typename Visit>
  void near(double x, double y, Visit visit) const {
    const int cx = cell(x - min_x_), cy = cell(y - min_y_);
    for (int row = std::max(cy - 1, 0); row <= std::min(cy + 1, rows_ - 1); ++row)
      for (int column = std::max(cx - 1, 0); column <= std::min(cx + 1, columns_ - 1); ++column)
        for (const std::uint32_t i :
             cells_[static_cast<std::size_t>(row) * columns_ + static_cast<std::size_t>(column)])
          if (std::hypot(keypoints_[i].x - x, keypoints_[i].y - y) <= kReappearanceRadius) visit(i);
  }

 private:
  static int cell(double offset) { return static_cast<int>(offset / kReappearanceRadius); }

  Span<Keypoint> keypoints_;
  float min_x_ = 0, max_x_ = 0, min_y_ = 0, max_y_ = 0;
  int columns_ = 1, rows_ = 1;
  std::vector<std::vector<std::uint32_t>> cells_;
};

// The share of `from`'s features that `mapping` puts within `to`'s extent
// and that find a similar feature of `to` there.
double reappearing_share(Span<Keypoint> from, const DescriptorView& from_descriptors,
                         const KeypointGrid& to, const DescriptorView& to_descriptors,
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
    p.emplace_back(first[c.first].x, first[c.first].y);
    q.emplace_back(second[c.second].x, second[c.second].y);
  }
  const cv::Mat found = cv::findHomography(p, q, cv::RANSAC, kHomographyTolerance);
  if (found.rows != 3 || found.cols != 3) return 0;
  cv::Matx33d homography;
  found.convertTo(cv::Mat(3, 3, CV_64F, homography.val), CV_64F);
  bool invertible = false;
  const cv::Matx33d inverse = homography.inv(cv::DECOMP_LU, &invertible);
  if (!invertible) return 0;
  const KeypointGrid first_grid(first), second_grid(second);
  return std::min(
      reappearing_share(first, first_descriptors, second_grid, second_descriptors, homography),
      reappearing_share(second, second_descriptors, first_grid, first_descriptors, inverse));
}

}  // namespace binbow::vision
