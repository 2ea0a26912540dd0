#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/calib3d.hpp>

#include "binbow/error.h"
#include "binbow/vision/geometric_check.h"

namespace binbow::vision {
namespace {

using Vec9 = cv::Matx<double, 9, 1>;

// The inliers kept by distinct_inliers(), in input order.
std::vector<Correspondence> distinct_correspondences(Span<Keypoint> first, Span<Keypoint> second,
                                                     const std::vector<Correspondence>& inliers) {
  constexpr float r2 = kDistinctInlierRadius * kDistinctInlierRadius;
  const auto near = [](const Keypoint& a, const Keypoint& b) {
    const float dx = a.x - b.x, dy = a.y - b.y;
    return dx * dx + dy * dy <= r2;
  };
  std::vector<Correspondence> kept;
  for (const Correspondence& c : inliers) {
    if (c.first >= first.size() || c.second >= second.size())
      throw InvalidArgument("correspondence refers to a keypoint past the end");
    const bool repeated = std::any_of(kept.begin(), kept.end(), [&](const Correspondence& k) {
      return near(first[c.first], first[k.first]) || near(second[c.second], second[k.second]);
    });
    if (!repeated) kept.push_back(c);
  }
  return kept;
}

// Width and height of the bounding box of points.
struct Extent {
  double width = 0, height = 0;
};

template <typename Points>
Extent extent_of(const Points& points) {
  double min_x = points[0].x, max_x = min_x, min_y = points[0].y, max_y = min_y;
  for (const auto& p : points) {
    min_x = std::min<double>(min_x, p.x);
    max_x = std::max<double>(max_x, p.x);
    min_y = std::min<double>(min_y, p.y);
    max_y = std::max<double>(max_y, p.y);
  }
  return {max_x - min_x, max_y - min_y};
}

// What the inliers are judged against, from all of an image's keypoints:
// Hartley's normalisation (their centroid to the origin, their mean
// distance from it √2), so that the alternatives are different geometries
// of the whole view, not of the inliers' part of it; and their extent.
struct View {
  cv::Matx33d normalisation;
  Extent extent;
};

View view_of(Span<Keypoint> keypoints) {
  cv::Point2d centre(0, 0);
  for (const Keypoint& k : keypoints) centre += cv::Point2d(k.x, k.y);
  centre *= 1.0 / static_cast<double>(keypoints.size());
  double mean_distance = 0;
  for (const Keypoint& k : keypoints) mean_distance += cv::norm(cv::Point2d(k.x, k.y) - centre);
  mean_distance /= static_cast<double>(keypoints.size());
  const double s = mean_distance > 0 ? std::sqrt(2.0) / mean_distance : 1.0;
  return {{s, 0, -s * centre.x, 0, s, -s * centre.y, 0, 0, 1}, extent_of(keypoints)};
}

cv::Point2d apply(const cv::Matx33d& t, const cv::Point2d& p) {
  return {t(0, 0) * p.x + t(0, 2), t(1, 1) * p.y + t(1, 2)};
}

// The two solutions of `system` (rows of 9 unknowns) halfway (45°) between
// its least-squares solution (the right singular vector of the smallest
// singular value) and the best solution orthogonal to it (the second
// smallest): when the system leaves a family of solutions open, these are
// members of it as different from the best as they are similar.
void alternatives_of(const cv::Mat& system, Vec9 (&alternatives)[2]) {
  cv::Mat w, u, vt;
  cv::SVD::compute(system, w, u, vt, cv::SVD::FULL_UV);
  for (int i = 0; i < 9; ++i) {
    alternatives[0](i) = vt.at<double>(8, i) + vt.at<double>(7, i);
    alternatives[1](i) = vt.at<double>(8, i) - vt.at<double>(7, i);
  }
}

cv::Matx33d as_matrix(const Vec9& v) {
  return {v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7), v(8)};
}

// Points within `tolerance` of their epipolar lines, both ways.
std::size_t fundamental_fits(const cv::Matx33d& f, const std::vector<cv::Point2d>& p,
                             const std::vector<cv::Point2d>& q, double tolerance) {
  std::size_t fits = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const cv::Vec3d x(p[i].x, p[i].y, 1), y(q[i].x, q[i].y, 1);
    const cv::Vec3d line_second = f * x, line_first = f.t() * y;
    const double algebraic = std::abs(y.dot(line_second));
    const double n_second = std::hypot(line_second[0], line_second[1]);
    const double n_first = std::hypot(line_first[0], line_first[1]);
    if (n_second > 0 && n_first > 0 && algebraic <= tolerance * n_second &&
        algebraic <= tolerance * n_first)
      ++fits;
  }
  return fits;
}

// Whether `h` maps each point within `tolerance` of its partner, both ways
// (none when h is singular).
std::vector<bool> homography_inliers(const cv::Matx33d& h, const std::vector<cv::Point2d>& p,
                                     const std::vector<cv::Point2d>& q, double tolerance) {
  std::vector<bool> inlier(p.size(), false);
  bool invertible = false;
  const cv::Matx33d inverse = h.inv(cv::DECOMP_LU, &invertible);
  if (!invertible) return inlier;
  const auto maps_within = [tolerance](const cv::Matx33d& m, const cv::Point2d& from,
                                       const cv::Point2d& to) {
    const cv::Vec3d x = m * cv::Vec3d(from.x, from.y, 1);
    if (!(std::abs(x[2]) > std::numeric_limits<double>::epsilon())) return false;
    return std::hypot(x[0] / x[2] - to.x, x[1] / x[2] - to.y) <= tolerance;
  };
  for (std::size_t i = 0; i < p.size(); ++i)
    inlier[i] = maps_within(h, p[i], q[i]) && maps_within(inverse, q[i], p[i]);
  return inlier;
}

// Whether most of `points` lie within `tolerance` of their total least
// squares line.
bool near_one_line(const std::vector<cv::Point2d>& points, double tolerance) {
  cv::Point2d mean(0, 0);
  for (const cv::Point2d& p : points) mean += p;
  mean *= 1.0 / static_cast<double>(points.size());
  double xx = 0, xy = 0, yy = 0;
  for (const cv::Point2d& p : points) {
    const cv::Point2d d = p - mean;
    xx += d.x * d.x;
    xy += d.x * d.y;
    yy += d.y * d.y;
  }
  // The normal of the line: the eigenvector of the smaller eigenvalue.
  const double angle = 0.5 * std::atan2(2 * xy, xx - yy);
  const cv::Point2d normal(-std::sin(angle), std::cos(angle));
  std::size_t near = 0;
  for (const cv::Point2d& p : points) near += std::abs((p - mean).dot(normal)) <= tolerance;
  return static_cast<double>(near) >= kAmbiguousShare * static_cast<double>(points.size());
}

// Whether the bounding box of `points` fits in one cell of the
// kSpreadGridCells × kSpreadGridCells grid over the view.
bool within_one_cell(const std::vector<cv::Point2d>& points, const View& view) {
  const Extent e = extent_of(points);
  return e.width * kSpreadGridCells <= view.extent.width &&
         e.height * kSpreadGridCells <= view.extent.height;
}

bool most(std::size_t fits, std::size_t points) {
  return static_cast<double>(fits) >= kAmbiguousShare * static_cast<double>(points);
}

// More points than a fundamental matrix (7) and a homography (4) need: the
// fewest that test the model at all.
constexpr std::size_t kMinFundamentalPoints = 8;
constexpr std::size_t kMinHomographyPoints = 5;

}  // namespace

const char* to_string(FitEvidence evidence) {
  switch (evidence) {
    case FitEvidence::kNone:
      return "none";
    case FitEvidence::kFundamental:
      return "fundamental";
    case FitEvidence::kHomography:
      return "homography";
    case FitEvidence::kDegenerate:
      return "degenerate";
  }
  return "?";
}

std::size_t distinct_inliers(Span<Keypoint> first, Span<Keypoint> second,
                             const std::vector<Correspondence>& inliers) {
  return distinct_correspondences(first, second, inliers).size();
}

FitDeterminacy fit_determinacy(Span<Keypoint> first, Span<Keypoint> second,
                               const std::vector<Correspondence>& inliers, double tolerance) {
  if (!(tolerance > 0) || !std::isfinite(tolerance))
    throw InvalidArgument("fit_determinacy: the tolerance must be a positive number of pixels");
  FitDeterminacy out;
  const std::vector<Correspondence> distinct = distinct_correspondences(first, second, inliers);
  if (distinct.empty()) return out;
  out.points = distinct.size();
  std::vector<cv::Point2d> p, q;
  for (const Correspondence& c : distinct) {
    p.emplace_back(first[c.first].x, first[c.first].y);
    q.emplace_back(second[c.second].x, second[c.second].y);
  }
  const View first_view = view_of(first), second_view = view_of(second);
  const cv::Matx33d &tp = first_view.normalisation, &tq = second_view.normalisation;
  const int n = static_cast<int>(p.size());
  const double point_tolerance = tolerance * std::sqrt(2.0);

  out.alternative_fundamental_fits = out.points;
  out.evidence = FitEvidence::kDegenerate;
  if (out.points >= kMinFundamentalPoints) {
    cv::Mat system(n, 9, CV_64F);
    for (int i = 0; i < n; ++i) {
      const cv::Point2d a = apply(tp, p[i]), b = apply(tq, q[i]);
      const double row[9] = {b.x * a.x, b.x * a.y, b.x, b.y * a.x, b.y * a.y, b.y, a.x, a.y, 1};
      std::copy(row, row + 9, system.ptr<double>(i));
    }
    Vec9 alternatives[2];
    alternatives_of(system, alternatives);
    out.alternative_fundamental_fits = 0;
    for (const Vec9& f : alternatives)
      out.alternative_fundamental_fits =
          std::max(out.alternative_fundamental_fits,
                   fundamental_fits(tq.t() * as_matrix(f) * tp, p, q, tolerance));
    out.fundamental_determined = !most(out.alternative_fundamental_fits, out.points);
    if (out.fundamental_determined) {
      // The probe at 45° can miss a narrow configuration's freedom: a line or a
      // patch within the tolerance is degenerate whatever it says.
      out.on_a_line = near_one_line(p, point_tolerance) || near_one_line(q, point_tolerance);
      out.on_a_patch = within_one_cell(p, first_view) || within_one_cell(q, second_view);
      if (!out.on_a_line && !out.on_a_patch) out.evidence = FitEvidence::kFundamental;
      return out;
    }
  }

  if (out.points < kMinHomographyPoints) return out;
  // The homography most points follow (the others may be parallax, or fit
  // only some other member of the fundamental matrices' family).
  const cv::Mat found = cv::findHomography(p, q, cv::RANSAC, point_tolerance, cv::noArray(), 2000);
  if (found.rows != 3 || found.cols != 3) return out;
  cv::Matx33d homography;
  found.convertTo(cv::Mat(3, 3, CV_64F, homography.val), CV_64F);
  const std::vector<bool> on_plane = homography_inliers(homography, p, q, point_tolerance);
  std::vector<cv::Point2d> on_plane_p, on_plane_q;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (on_plane[i]) {
      on_plane_p.push_back(p[i]);
      on_plane_q.push_back(q[i]);
    }
  out.homography_fits = on_plane_p.size();
  if (out.homography_fits < kMinHomographyPoints) return out;
  out.on_a_line =
      near_one_line(on_plane_p, point_tolerance) || near_one_line(on_plane_q, point_tolerance);
  out.on_a_patch =
      within_one_cell(on_plane_p, first_view) || within_one_cell(on_plane_q, second_view);
  if (!out.on_a_line && !out.on_a_patch) out.evidence = FitEvidence::kHomography;
  return out;
}

}  // namespace binbow::vision
