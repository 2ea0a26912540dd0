// Whether a fit's inliers determine its geometry (fit_determinacy): point
// sets made degenerate on purpose (a line, a thin band, a small patch of
// texture, copies of a few corners, conics paired at random) are no evidence, while
// genuine views with the same number of points are: a 3-D scene (the
// fundamental matrix) and a plane (a homography).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "binbow/error.h"
#include "binbow/vision/geometric_check.h"

namespace binbow::vision {
namespace {

// Two views of points: keypoints of each image and the pairing. Each image
// also has 200 keypoints spread over it that pair with nothing, as a real
// image has: the geometry is judged over the whole view.
struct Views {
  Views() {
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> x(0, 640), y(0, 480);
    for (int i = 0; i < 200; ++i) {
      first.push_back({x(rng), y(rng), 31, 0, 1, 0});
      second.push_back({x(rng), y(rng), 31, 0, 1, 0});
    }
  }
  std::vector<Keypoint> first, second;
  std::vector<Correspondence> pairs;
  Span<Keypoint> a() const { return {first.data(), first.size()}; }
  Span<Keypoint> b() const { return {second.data(), second.size()}; }
  void add(cv::Point2d p, cv::Point2d q) {
    pairs.push_back(
        {static_cast<std::uint32_t>(first.size()), static_cast<std::uint32_t>(second.size())});
    first.push_back({static_cast<float>(p.x), static_cast<float>(p.y), 31, 0, 1, 0});
    second.push_back({static_cast<float>(q.x), static_cast<float>(q.y), 31, 0, 1, 0});
  }
};

constexpr double kTolerance = 2.0;  // LoopDetectorParams::max_reprojection_error

// A pinhole camera of a 640x480 image (f = 500) at `centre`, turned by `yaw` radians.
cv::Point2d project(const cv::Vec3d& point, const cv::Vec3d& centre, double yaw) {
  const cv::Vec3d d = point - centre;
  const double x = std::cos(yaw) * d[0] - std::sin(yaw) * d[2];
  const double z = std::sin(yaw) * d[0] + std::cos(yaw) * d[2];
  return {320 + 500 * x / z, 240 + 500 * d[1] / z};
}

cv::Point2d jitter(cv::Point2d p, std::mt19937& rng, double sigma) {
  std::normal_distribution<double> noise(0, sigma);
  return {p.x + noise(rng), p.y + noise(rng)};
}

// `count` points spread through a room 4–10 m deep, seen from two places.
Views scene(int count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-3, 3), y(-2, 2), z(4, 10);
  Views v;
  while (v.pairs.size() < static_cast<std::size_t>(count)) {
    // One statement per draw: the order of arguments' evaluation is the compiler's.
    const double px = x(rng), py = y(rng), pz = z(rng);
    const cv::Vec3d point(px, py, pz);
    const cv::Point2d a = jitter(project(point, {0, 0, 0}, 0), rng, 0.3);
    const cv::Point2d b = jitter(project(point, {0.8, 0.1, 0.5}, 0.12), rng, 0.3);
    v.add(a, b);
  }
  return v;
}

// `count` points of one wall (z = 6 m), seen from two places.
Views plane(int count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-3, 3), y(-2, 2);
  Views v;
  for (int i = 0; i < count; ++i) {
    const double px = x(rng), py = y(rng);
    const cv::Vec3d point(px, py, 6);
    const cv::Point2d a = jitter(project(point, {0, 0, 0}, 0), rng, 0.3);
    const cv::Point2d b = jitter(project(point, {0.8, 0.1, 0.5}, 0.12), rng, 0.3);
    v.add(a, b);
  }
  return v;
}

// Points within `half_width` pixels of a 300-pixel segment in each image,
// paired in order along it (a pipe, a skirting board, the edge of a shelf).
Views band(int count, double half_width, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> along(0, 1), across(-half_width, half_width);
  Views v;
  for (int i = 0; i < count; ++i) {
    const double t = along(rng);
    v.add({100 + 300 * t, 200 + 80 * t + across(rng)}, {150 + 280 * t, 260 - 40 * t + across(rng)});
  }
  return v;
}

// Points in a `size`-pixel square, shifted between the images (a patch of texture).
Views patch(int count, double size, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> offset(0, size);
  Views v;
  for (int i = 0; i < count; ++i) {
    const double px = offset(rng), py = offset(rng);
    const cv::Point2d p(300 + px, 200 + py);
    v.add(p, jitter(p + cv::Point2d(-48, 13), rng, 0.5));
  }
  return v;
}

// Twelve points are the edge of what determines a fundamental matrix at
// 2 pixels: in some draws a matrix 45° away still fits 10 of them. With
// twenty, every draw determines it.
TEST(FitEvidence, AGenuineSceneDeterminesTheFundamentalMatrix) {
  for (const int count : {12, 20}) {
    int determined = 0;
    for (std::uint32_t seed = 1; seed <= 20; ++seed) {
      const Views v = scene(count, seed);
      const FitDeterminacy d = fit_determinacy(v.a(), v.b(), v.pairs, kTolerance);
      EXPECT_GE(d.points + 1, static_cast<std::size_t>(count));  // two may fall within 3 px
      EXPECT_NE(d.evidence, FitEvidence::kNone);
      determined += d.evidence == FitEvidence::kFundamental;
    }
    EXPECT_GE(determined, count == 12 ? 15 : 20) << count << " points";
  }
}

TEST(FitEvidence, AGenuinePlaneDeterminesAHomography) {
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    const Views v = plane(12, seed);
    const FitDeterminacy d = fit_determinacy(v.a(), v.b(), v.pairs, kTolerance);
    EXPECT_EQ(d.evidence, FitEvidence::kHomography) << "seed " << seed;
    EXPECT_GE(d.homography_fits, 11u);
    EXPECT_FALSE(d.on_a_line);
    EXPECT_FALSE(d.on_a_patch);
  }
}

TEST(FitEvidence, PointsOnOrNearALineAreDegenerate) {
  for (std::uint32_t seed = 1; seed <= 20; ++seed)
    for (const double half_width : {0.0, 0.5, 1.0}) {
      const Views v = band(40, half_width, seed);
      const FitDeterminacy d = fit_determinacy(v.a(), v.b(), v.pairs, kTolerance);
      EXPECT_EQ(d.evidence, FitEvidence::kDegenerate)
          << "seed " << seed << ", band of ±" << half_width << " px: " << d.points
          << " points, alternative F " << d.alternative_fundamental_fits << ", H "
          << d.homography_fits << ", line " << d.on_a_line << ", patch " << d.on_a_patch;
    }
}

TEST(FitEvidence, PointsOnOneSmallPatchAreDegenerate) {
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    const Views v = patch(30, 20, seed);
    const FitDeterminacy d = fit_determinacy(v.a(), v.b(), v.pairs, kTolerance);
    EXPECT_EQ(d.evidence, FitEvidence::kDegenerate)
        << "seed " << seed << ": " << d.points << " points, alternative F "
        << d.alternative_fundamental_fits << ", H " << d.homography_fits << ", line " << d.on_a_line
        << ", patch " << d.on_a_patch;
  }
}

TEST(FitEvidence, CopiesOfSevenCornersAreDegenerate) {
  // Seven points of a genuine scene, each described at three pyramid levels
  // (copies within a pixel): 21 inliers, 7 points, which any fundamental matrix fits.
  const Views seven = scene(7, 3);
  Views v;
  for (int copy = 0; copy < 3; ++copy)
    for (const Correspondence& c : seven.pairs)
      v.add({seven.first[c.first].x + 0.5 * copy, seven.first[c.first].y},
            {seven.second[c.second].x, seven.second[c.second].y - 0.5 * copy});
  const FitDeterminacy d = fit_determinacy(v.a(), v.b(), v.pairs, kTolerance);
  EXPECT_EQ(d.points, 7u);
  EXPECT_EQ(d.evidence, FitEvidence::kDegenerate);
}

TEST(FitEvidence, ConicsPairedAtRandomAreDegenerateAndAConicOnAPlaneIsAHomography) {
  std::mt19937 rng(5);
  Views random_pairs;
  std::vector<int> order(24);
  for (int i = 0; i < 24; ++i) order[static_cast<std::size_t>(i)] = i;
  std::shuffle(order.begin(), order.end(), rng);
  const auto on_ellipse = [](int i, cv::Point2d centre, double a, double b) {
    const double t = 2 * M_PI * i / 24;
    return centre + cv::Point2d(a * std::cos(t), b * std::sin(t));
  };
  for (int i = 0; i < 24; ++i)
    random_pairs.add(on_ellipse(i, {320, 240}, 150, 90),
                     on_ellipse(order[static_cast<std::size_t>(i)], {300, 250}, 120, 100));
  const FundamentalCheckResult fit =
      check_fundamental(random_pairs.a(), random_pairs.b(), random_pairs.pairs, {});
  EXPECT_FALSE(fit.consistent) << fit.inliers.size() << " inliers";

  // A round sign on a wall, seen from two places: its points follow one homography.
  Views sign;
  for (int i = 0; i < 24; ++i) {
    const double t = 2 * M_PI * i / 24;
    const cv::Vec3d point(1.5 * std::cos(t), 1.5 * std::sin(t), 6);
    sign.add(project(point, {0, 0, 0}, 0), project(point, {0.8, 0.1, 0.5}, 0.12));
  }
  EXPECT_EQ(fit_determinacy(sign.a(), sign.b(), sign.pairs, kTolerance).evidence,
            FitEvidence::kHomography);
}

TEST(FitEvidence, NoInliersNoEvidenceAndBadArgumentsThrow) {
  const Views v = scene(12, 1);
  EXPECT_EQ(fit_determinacy(v.a(), v.b(), {}, kTolerance).evidence, FitEvidence::kNone);
  EXPECT_THROW(fit_determinacy(v.a(), v.b(), v.pairs, 0), InvalidArgument);
  EXPECT_THROW(fit_determinacy(v.a(), v.b(), v.pairs, std::nan("")), InvalidArgument);
  EXPECT_THROW(fit_determinacy(v.a(), v.b(), {{1000, 0}}, kTolerance), InvalidArgument);
  EXPECT_STREQ(to_string(FitEvidence::kDegenerate), "degenerate");
  EXPECT_STREQ(to_string(FitEvidence::kHomography), "homography");
}

// The rule, not the estimator, rejects: the same degenerate correspondences
// give a consistent fit when degenerate fits are let through.
TEST(FitEvidence, CheckFundamentalRejectsADegenerateFitWhateverItsInliers) {
  for (std::uint32_t seed = 1; seed <= 10; ++seed) {
    const Views thick = band(60, 1.5, seed);
    const FundamentalCheckResult r = check_fundamental(thick.a(), thick.b(), thick.pairs, {});
    EXPECT_NE(r.determinacy.evidence, FitEvidence::kFundamental) << "seed " << seed;
    EXPECT_FALSE(r.consistent) << "seed " << seed;
  }
  const Views line = band(40, 1.0, 7);
  FundamentalCheckParams params;
  params.estimator = FundamentalEstimator::kUsacMagsac;
  const FundamentalCheckResult rejected = check_fundamental(line.a(), line.b(), line.pairs, params);
  EXPECT_GE(rejected.inliers.size(), 12u);
  EXPECT_EQ(rejected.determinacy.evidence, FitEvidence::kDegenerate);
  EXPECT_FALSE(rejected.consistent);
  params.reject_degenerate = false;
  EXPECT_TRUE(check_fundamental(line.a(), line.b(), line.pairs, params).consistent);

  params.reject_degenerate = true;
  const Views genuine = scene(12, 7);
  const FundamentalCheckResult accepted =
      check_fundamental(genuine.a(), genuine.b(), genuine.pairs, params);
  EXPECT_TRUE(accepted.consistent);
  EXPECT_EQ(accepted.determinacy.evidence, FitEvidence::kFundamental);
}

}  // namespace
}  // namespace binbow::vision
