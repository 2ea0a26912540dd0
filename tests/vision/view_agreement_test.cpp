// How much of two views a fit explains (view_agreement): views of one place
// show their features again where the fit's homography puts them; views of
// two places that share only a repeated object (the same lamps and doors a
// corridor's length apart) do not, whatever the number of inliers on the
// repeated objects.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "binbow/descriptors.h"
#include "binbow/error.h"
#include "binbow/vision/geometric_check.h"

namespace binbow::vision {
namespace {

constexpr std::size_t kCodeSize = 32;

std::vector<std::uint8_t> random_code(std::mt19937& rng) {
  std::vector<std::uint8_t> code(kCodeSize);
  for (std::uint8_t& byte : code) byte = static_cast<std::uint8_t>(rng());
  return code;
}

// The same code with `bits` of its bits flipped (a re-detected corner's
// descriptor under other noise).
std::vector<std::uint8_t> with_noise(std::vector<std::uint8_t> code, int bits, std::mt19937& rng) {
  for (int i = 0; i < bits; ++i)
    code[rng() % kCodeSize] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
  return code;
}

struct Image {
  std::vector<Keypoint> keypoints;
  DescriptorMatrix descriptors{kCodeSize};
  Span<Keypoint> points() const { return {keypoints.data(), keypoints.size()}; }
  void add(double x, double y, const std::vector<std::uint8_t>& code) {
    keypoints.push_back({static_cast<float>(x), static_cast<float>(y), 31, -1, 1, 0});
    descriptors.append(code.data());
  }
};

// A 640 × 480 view: 12 repeated objects (lamps, doors) whose pairs are the
// inliers, and `unique` features of the place. The second image shows the
// repeated objects shifted by (8, 5) pixels (the camera turned a little);
// with `same_place` its other features are the first image's, shifted the
// same way and re-detected with noise, otherwise another place's.
struct Pair {
  Image first, second;
  std::vector<Correspondence> inliers;
};

Pair views(bool same_place, int unique = 150) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(20, 620), y(20, 460);
  Pair p;
  for (int i = 0; i < 12; ++i) {
    const double u = 60 + 45 * i, v = (i % 2 == 0 ? 80 : 380) + 3 * i;
    const std::vector<std::uint8_t> code = random_code(rng);
    p.inliers.push_back({static_cast<std::uint32_t>(p.first.keypoints.size()),
                         static_cast<std::uint32_t>(p.second.keypoints.size())});
    p.first.add(u, v, code);
    p.second.add(u + 8, v + 5, with_noise(code, 6, rng));
  }
  for (int i = 0; i < unique; ++i) {
    const double u = x(rng), v = y(rng);
    const std::vector<std::uint8_t> code = random_code(rng);
    p.first.add(u, v, code);
    if (same_place)
      p.second.add(u + 8, v + 5, with_noise(code, 10, rng));
    else
      p.second.add(x(rng), y(rng), random_code(rng));
  }
  return p;
}

double agreement(const Pair& p) {
  return view_agreement(p.first.points(), p.first.descriptors.view(), p.second.points(),
                        p.second.descriptors.view(), p.inliers);
}

TEST(ViewAgreement, ViewsOfOnePlaceShowTheirFeaturesAgain) {
  EXPECT_GT(agreement(views(true)), 0.9);
}

TEST(ViewAgreement, RepeatedObjectsOfTwoPlacesExplainOnlyThemselves) {
  // 12 of 162 features reappear (the repeated objects), in each direction.
  const double share = agreement(views(false));
  EXPECT_GT(share, 0.05);
  EXPECT_LT(share, 0.15);
}

TEST(ViewAgreement, TheSameInliersScoreTheViewsNotTheInliers) {
  // Both pairs have the same 12 inliers: only the rest of the views differ.
  EXPECT_GT(agreement(views(true)), 3 * agreement(views(false)));
}

TEST(ViewAgreement, FewerThanFourDistinctInliersAgreeOnNothing) {
  Pair p = views(true);
  p.inliers.resize(3);
  EXPECT_EQ(agreement(p), 0.0);
  p.inliers.clear();
  EXPECT_EQ(agreement(p), 0.0);
}

TEST(ViewAgreement, StrayCoordinatesChangeNothingElse) {
  // A caller's keypoints far away or not numbers at all (LoopDetector takes
  // any): they land nowhere, and cost no memory by their distance.
  Pair p = views(true);
  std::mt19937 rng(3);
  p.second.add(1e30, 5, random_code(rng));
  p.second.add(std::nan(""), 5, random_code(rng));
  p.first.add(-1e30, std::numeric_limits<double>::infinity(), random_code(rng));
  EXPECT_GT(agreement(p), 0.85);
  // Inliers that are not numbers give no homography.
  p.inliers.push_back({static_cast<std::uint32_t>(p.first.keypoints.size() - 1),
                       static_cast<std::uint32_t>(p.second.keypoints.size() - 1)});
  EXPECT_EQ(agreement(p), 0.0);
}

TEST(ViewAgreement, MismatchedKeypointsAndDescriptorsAreRefused) {
  Pair p = views(true);
  p.first.keypoints.pop_back();
  EXPECT_THROW(agreement(p), InvalidArgument);
}

}  // namespace
}  // namespace binbow::vision
