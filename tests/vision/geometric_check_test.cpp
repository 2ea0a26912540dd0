#include "binbow/vision/geometric_check.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/core/persistence.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "binbow/error.h"
#include "support/test_support.h"

namespace binbow::vision {
namespace {

using test::shared_data;

struct ImageFeatures {
  std::vector<Keypoint> keypoints;
  DescriptorMatrix descriptors{32};
  Span<Keypoint> points() const { return {keypoints.data(), keypoints.size()}; }
};

ImageFeatures orb(const std::string& name) {
  const cv::Mat image = cv::imread(shared_data("opencv-doc-samples/" + name), cv::IMREAD_GRAYSCALE);
  EXPECT_FALSE(image.empty()) << name;
  std::vector<cv::KeyPoint> keys;
  cv::Mat descriptors;
  cv::ORB::create(1000)->detectAndCompute(image, cv::noArray(), keys, descriptors);
  ImageFeatures f;
  for (const cv::KeyPoint& k : keys)
    f.keypoints.push_back({k.pt.x, k.pt.y, k.size, k.angle, k.response, k.octave});
  f.descriptors =
      DescriptorMatrix(descriptors.data, static_cast<std::size_t>(descriptors.rows), 32);
  return f;
}

FundamentalCheckResult verify(const ImageFeatures& a, const ImageFeatures& b) {
  const auto matches = match_exhaustive(a.descriptors, b.descriptors);
  return check_fundamental(a.points(), b.points(), matches);
}

TEST(GeometricCheck, KnownHomographyPairIsConsistentAndInliersFollowIt) {
  const ImageFeatures a = orb("graf1.png"), b = orb("graf3.png");
  const FundamentalCheckResult r = verify(a, b);
  ASSERT_TRUE(r.consistent);
  cv::FileStorage fs(shared_data("opencv-doc-samples/H1to3p.xml"), cv::FileStorage::READ);
  cv::Mat h;
  fs["H13"] >> h;
  ASSERT_EQ(h.rows, 3);
  std::size_t agreeing = 0;
  for (const Correspondence& c : r.inliers) {
    const Keypoint& p = a.keypoints[c.first];
    const Keypoint& q = b.keypoints[c.second];
    const cv::Mat x = h * (cv::Mat_<double>(3, 1) << p.x, p.y, 1.0);
    const double dx = x.at<double>(0) / x.at<double>(2) - q.x;
    const double dy = x.at<double>(1) / x.at<double>(2) - q.y;
    if (dx * dx + dy * dy < 5.0 * 5.0) ++agreeing;
  }
  EXPECT_GE(agreeing * 10, r.inliers.size() * 8) << agreeing << " of " << r.inliers.size();
  // Epipolar constraint of the returned F on the inliers.
  for (const Correspondence& c : r.inliers) {
    const cv::Vec3d x1(a.keypoints[c.first].x, a.keypoints[c.first].y, 1);
    const cv::Vec3d x2(b.keypoints[c.second].x, b.keypoints[c.second].y, 1);
    const cv::Vec3d line = r.fundamental * x1;
    const double distance = std::abs(x2.dot(line)) / std::hypot(line[0], line[1]);
    EXPECT_LT(distance, 2.5);
  }
}

TEST(GeometricCheck, OtherViewsOfOneSceneAreConsistent) {
  for (const auto& [first, second] : std::vector<std::pair<const char*, const char*>>{
           {"leuvenA.jpg", "leuvenB.jpg"},
           {"rubberwhale1.png", "rubberwhale2.png"},
           {"basketball1.png", "basketball2.png"},
           {"Blender_Suzanne1.jpg", "Blender_Suzanne2.jpg"}}) {
    const FundamentalCheckResult r = verify(orb(first), orb(second));
    EXPECT_TRUE(r.consistent) << first << " " << second << ": " << r.inliers.size() << " inliers";
  }
}

TEST(GeometricCheck, UnrelatedPairsAreNotConsistent) {
  for (const auto& [first, second] :
       std::vector<std::pair<const char*, const char*>>{{"graf1.png", "box_in_scene.png"},
                                                        {"aero1.jpg", "leuvenA.jpg"},
                                                        {"box.png", "basketball1.png"},
                                                        {"graf3.png", "aero3.jpg"},
                                                        {"leuvenB.jpg", "rubberwhale1.png"}}) {
    const FundamentalCheckResult r = verify(orb(first), orb(second));
    EXPECT_FALSE(r.consistent) << first << " " << second << ": " << r.inliers.size() << " inliers";
  }
}

TEST(GeometricCheck, TooFewCorrespondencesAreNotTried) {
  const std::vector<Keypoint> points(20);
  const Span<Keypoint> span{points.data(), points.size()};
  std::vector<Correspondence> few;
  for (std::uint32_t i = 0; i < 11; ++i) few.push_back({i, i});
  EXPECT_FALSE(check_fundamental(span, span, few).consistent);
  EXPECT_THROW(check_fundamental(span, span, std::vector<Correspondence>(12, {25, 0})),
               InvalidArgument);
}

// Reference ratio-test matcher straight from the definition.
std::vector<Correspondence> reference_matches(
    const DescriptorView& a, const std::vector<std::uint32_t>& ia, const DescriptorView& b,
    const std::vector<std::uint32_t>& ib, double ratio,
    std::vector<std::pair<Correspondence, std::uint32_t>>& out) {
  for (std::uint32_t i : ia) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> d;
    for (std::uint32_t j : ib) d.emplace_back(hamming_distance(a.row(i), b.row(j), a.code_size), j);
    if (d.empty()) continue;
    std::stable_sort(d.begin(), d.end(), [](auto x, auto y) { return x.first < y.first; });
    const bool pass =
        d.size() == 1 || (d[0].first < d[1].first && d[0].first <= ratio * d[1].first);
    if (pass) out.push_back({{i, d[0].second}, d[0].first});
  }
  return {};
}

std::vector<Correspondence> keep_nearest_per_second(
    std::vector<std::pair<Correspondence, std::uint32_t>> m) {
  // For each feature of the second image, the first (in order) of its closest partners.
  std::vector<Correspondence> result;
  for (std::size_t x = 0; x < m.size(); ++x) {
    bool best = true;
    for (std::size_t y = 0; y < m.size(); ++y) {
      if (m[y].first.second != m[x].first.second || x == y) continue;
      if (m[y].second < m[x].second || (m[y].second == m[x].second && y < x)) best = false;
    }
    if (best) result.push_back(m[x].first);
  }
  std::sort(result.begin(), result.end(), [](auto p, auto q) { return p.first < q.first; });
  return result;
}

// 32 bytes takes the popcnt kernel, other sizes the generic one.
class Matching : public testing::TestWithParam<std::size_t> {};

TEST_P(Matching, ExhaustiveAndDirectIndexMatchTheDefinition) {
  std::mt19937_64 rng(3);
  const std::size_t code_size = GetParam();
  for (int trial = 0; trial < 20; ++trial) {
    const DescriptorMatrix a = test::clustered_descriptors(120, code_size, 15, 0.1, rng);
    const DescriptorMatrix b = test::clustered_descriptors(100, code_size, 15, 0.1, rng);
    std::vector<std::uint32_t> all_a(a.rows()), all_b(b.rows());
    for (std::uint32_t i = 0; i < a.rows(); ++i) all_a[i] = i;
    for (std::uint32_t i = 0; i < b.rows(); ++i) all_b[i] = i;
    std::vector<std::pair<Correspondence, std::uint32_t>> raw;
    reference_matches(a, all_a, b, all_b, 0.8, raw);
    EXPECT_EQ(match_exhaustive(a, b, {0.8, 1.0}), keep_nearest_per_second(raw));

    // Random node assignment (8 nodes) for the direct index.
    std::vector<NodeId> node_a(a.rows()), node_b(b.rows());
    for (auto& n : node_a) n = static_cast<NodeId>(rng() % 8);
    for (auto& n : node_b) n = static_cast<NodeId>(rng() % 8);
    const FeatureVector fa = FeatureVector::from_assignment(node_a.data(), node_a.size());
    const FeatureVector fb = FeatureVector::from_assignment(node_b.data(), node_b.size());
    std::vector<std::pair<Correspondence, std::uint32_t>> per_node;
    for (NodeId n = 0; n < 8; ++n) {
      std::vector<std::uint32_t> ia, ib;
      for (std::uint32_t i = 0; i < a.rows(); ++i)
        if (node_a[i] == n) ia.push_back(i);
      for (std::uint32_t i = 0; i < b.rows(); ++i)
        if (node_b[i] == n) ib.push_back(i);
      reference_matches(a, ia, b, ib, 0.6, per_node);
    }
    // Nodes are disjoint, so no feature of b has two partners.
    auto expected = keep_nearest_per_second(per_node);
    EXPECT_EQ(match_direct_index(a, fa, b, fb), expected);
  }
}

INSTANTIATE_TEST_SUITE_P(CodeSizes, Matching, testing::Values(32, 64, 20));

TEST(MatchingArguments, RejectsBadArguments) {
  std::mt19937_64 rng(1);
  const DescriptorMatrix a = test::random_descriptors(5, 32, rng),
                         b = test::random_descriptors(5, 64, rng);
  EXPECT_THROW(match_exhaustive(a, b), InvalidArgument);
  EXPECT_THROW(match_exhaustive(a, a, {0, 1}), InvalidArgument);
  const NodeId nodes[6] = {0, 0, 1, 1, 2, 2};
  const FeatureVector too_many = FeatureVector::from_assignment(nodes, 6);
  EXPECT_THROW(match_direct_index(a, too_many, a, too_many), InvalidArgument);
  EXPECT_TRUE(match_exhaustive(a, DescriptorMatrix(32)).empty());
}

}  // namespace
}  // namespace binbow::vision

namespace binbow::vision {
namespace {

// Keypoints on a w x h frame; the four corners make the keypoints' box the
// whole frame.
std::vector<Keypoint> frame_corners_and(std::vector<Keypoint> points, float w, float h) {
  for (const Keypoint& corner : {Keypoint{0, 0}, Keypoint{w, 0}, Keypoint{0, h}, Keypoint{w, h}})
    points.push_back(corner);
  return points;
}

TEST(InlierSpread, CountsGridCellsAndTakesTheWorseImage) {
  // Image 1: inliers 0-3 in four different cells (one per quadrant); image 2:
  // the same four inliers clustered in one cell.
  const std::vector<Keypoint> spread =
      frame_corners_and({{10, 10}, {390, 10}, {10, 290}, {390, 290}}, 400, 300);
  const std::vector<Keypoint> clustered =
      frame_corners_and({{10, 10}, {12, 11}, {14, 12}, {16, 13}}, 400, 300);
  const Span<Keypoint> a{spread.data(), spread.size()}, b{clustered.data(), clustered.size()};
  const std::vector<Correspondence> inliers = {{0, 0}, {1, 1}, {2, 2}, {3, 3}};
  EXPECT_DOUBLE_EQ(inlier_spread(a, a, inliers), 4.0 / 16);
  EXPECT_DOUBLE_EQ(inlier_spread(b, b, inliers), 1.0 / 16);
  EXPECT_DOUBLE_EQ(inlier_spread(a, b, inliers), 1.0 / 16);
  EXPECT_DOUBLE_EQ(inlier_spread(a, b, {}), 0);
  EXPECT_THROW(inlier_spread(a, b, {{99, 0}}), InvalidArgument);
  // One keypoint (a degenerate box) is one occupied cell.
  const Keypoint single{5, 5};
  EXPECT_DOUBLE_EQ(inlier_spread({&single, 1}, {&single, 1}, {{0, 0}}), 1.0 / 16);
}

TEST(DistinctInliers, CopiesOfOneCornerCountOnce) {
  // Keypoints 0 and 1 are one corner at two pyramid levels (1 px apart) in
  // the first image; 2 is 2.8 px from 0 in the second image only; 3 is apart.
  const std::vector<Keypoint> first = {{10, 10}, {11, 10}, {50, 50}, {100, 10}};
  const std::vector<Keypoint> second = {{20, 20}, {60, 60}, {22, 22}, {200, 20}};
  const Span<Keypoint> a{first.data(), first.size()}, b{second.data(), second.size()};
  EXPECT_EQ(distinct_inliers(a, b, {{0, 0}, {1, 1}, {2, 2}, {3, 3}}), 2U);
  EXPECT_EQ(distinct_inliers(a, b, {{2, 1}, {3, 3}}), 2U);
  EXPECT_EQ(distinct_inliers(a, b, {}), 0U);
  EXPECT_THROW(distinct_inliers(a, b, {{0, 99}}), InvalidArgument);
}

TEST(InlierThickness, ZeroOnALineOneWithoutDirectionWorseImage) {
  const std::vector<Keypoint> line = {{0, 0}, {10, 10}, {20, 20}, {30, 30}};
  const std::vector<Keypoint> square = {{0, 0}, {10, 0}, {0, 10}, {10, 10}};
  // A 4 × 1 rectangle's corners: covariance eigenvalues 16 and 1.
  const std::vector<Keypoint> flat = {{0, 0}, {8, 0}, {0, 2}, {8, 2}};
  const std::vector<Correspondence> all = {{0, 0}, {1, 1}, {2, 2}, {3, 3}};
  const auto span = [](const std::vector<Keypoint>& k) {
    return Span<Keypoint>{k.data(), k.size()};
  };
  EXPECT_NEAR(inlier_thickness(span(line), span(line), all), 0, 1e-6);
  EXPECT_NEAR(inlier_thickness(span(square), span(square), all), 1, 1e-12);
  EXPECT_NEAR(inlier_thickness(span(flat), span(flat), all), 0.25, 1e-12);
  EXPECT_NEAR(inlier_thickness(span(square), span(flat), all), 0.25, 1e-12);
  EXPECT_EQ(inlier_thickness(span(square), span(square), {{0, 0}}), 0);
  EXPECT_THROW(inlier_thickness(span(square), span(square), {{0, 0}, {9, 1}}), InvalidArgument);
}

// First-image features 0 and 1 are identical: each is distinctive towards
// the second image (its nearest, second feature 0, is far nearer than the
// other), but second feature 0 has two equally near partners, so the pair
// fails the ratio test from the second image.
TEST(MutualMatching, DropsPairsDistinctiveOneWayOnly) {
  DescriptorMatrix first(32), second(32);
  first.resize(3);
  second.resize(2);
  std::fill(first.row(0), first.row(0) + 32, 0x00);
  std::fill(first.row(1), first.row(1) + 32, 0x00);
  std::fill(first.row(2), first.row(2) + 32, 0xFF);
  std::fill(second.row(0), second.row(0) + 32, 0x00);
  std::fill(second.row(1), second.row(1) + 32, 0xFF);
  second.row(1)[31] = 0xFE;
  MatchOptions options;
  EXPECT_EQ(match_exhaustive(first, second, options),
            (std::vector<Correspondence>{{0, 0}, {2, 1}}));
  options.mutual = true;
  EXPECT_EQ(match_exhaustive(first, second, options), (std::vector<Correspondence>{{2, 1}}));
}

TEST(GeometricCheck, EstimatorsAreDeterministicAndFindTheScene) {
  const ImageFeatures a = orb("graf1.png"), b = orb("graf3.png");
  const auto matches = match_exhaustive(a.descriptors, b.descriptors);
  for (const FundamentalEstimator estimator :
       {FundamentalEstimator::kRansac, FundamentalEstimator::kUsacMagsac,
        FundamentalEstimator::kUsacAccurate}) {
    SCOPED_TRACE(to_string(estimator));
    FundamentalCheckParams params;
    params.estimator = estimator;
    const FundamentalCheckResult first = check_fundamental(a.points(), b.points(), matches, params);
    const FundamentalCheckResult again = check_fundamental(a.points(), b.points(), matches, params);
    EXPECT_TRUE(first.consistent);
    EXPECT_EQ(first.inliers, again.inliers);
    EXPECT_GT(first.inlier_ratio, 0.5);
    EXPECT_GT(first.inlier_spread, 0.25);
    EXPECT_EQ(parse_fundamental_estimator(to_string(estimator)), estimator);
  }
  EXPECT_THROW(parse_fundamental_estimator("lmeds"), InvalidArgument);
}

TEST(GeometricCheck, InlierRatioAndSpreadThresholdsReject) {
  const ImageFeatures a = orb("graf1.png"), b = orb("graf3.png");
  const auto matches = match_exhaustive(a.descriptors, b.descriptors);
  FundamentalCheckParams params;
  const FundamentalCheckResult plain = check_fundamental(a.points(), b.points(), matches, params);
  ASSERT_TRUE(plain.consistent);
  ASSERT_LT(plain.inlier_spread, 1.0);
  params.min_inlier_ratio = std::nextafter(plain.inlier_ratio, 2.0);
  EXPECT_FALSE(check_fundamental(a.points(), b.points(), matches, params).consistent);
  params.min_inlier_ratio = plain.inlier_ratio;
  EXPECT_TRUE(check_fundamental(a.points(), b.points(), matches, params).consistent);
  params.min_inlier_spread = 1.0;
  EXPECT_FALSE(check_fundamental(a.points(), b.points(), matches, params).consistent);
  params.min_inlier_spread = 1.5;
  EXPECT_THROW(check_fundamental(a.points(), b.points(), matches, params), InvalidArgument);
}

}  // namespace
}  // namespace binbow::vision
