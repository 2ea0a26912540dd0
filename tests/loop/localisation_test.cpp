// Localisation within the island (LoopDetectorParams::localise_in_island) on
// rtabmap-samples upscaled 1.5x by OpenCV's bicubic resize, with BRIEF and the
// bundled vocabulary. Query 67 shares the most words with frame 32, a few
// metres back along the corridor, and fits a dozen of its repeated lamps and
// doors there; frames 25–29, where the camera is, fit many more of its
// features. Without localisation 67 → 32 is a false loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binbow/loop/decision_trail.h"
#include "binbow/loop/ground_truth.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/vision/geometric_check.h"
#include "loop/trailed_run.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

constexpr EntryId kQuery = 67;

// The 84 frames upscaled, written as PNG (lossless) into `dir`, named as the
// originals.
void write_upscaled_frames(const test::TempDir& dir) {
  for (int i = 1; i <= 84; ++i) {
    const std::string name = std::to_string(i);
    const cv::Mat original =
        cv::imread(test::samples_folder() + "/" + name + ".jpg", cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(original.empty()) << "cannot read frame " << name;
    cv::Mat upscaled;
    cv::resize(original, upscaled, cv::Size(), 1.5, 1.5, cv::INTER_CUBIC);
    ASSERT_TRUE(cv::imwrite(dir.file(name + ".png"), upscaled));
  }
}

test::TrailedRun detect(const std::string& folder, bool localise) {
  LoopDetectorParams params;
  params.localise_in_island = localise;
  return test::run_with_trails(folder, "brief", params);
}

class Localisation : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    truth_ =
        new GroundTruth(GroundTruth::load(test::shared_data("rtabmap-samples/samples_GT.bmp")));
    const test::TempDir dir;
    write_upscaled_frames(dir);
    without_ = new test::TrailedRun(detect(dir.path(), false));
    with_ = new test::TrailedRun(detect(dir.path(), true));
  }
  static void TearDownTestSuite() {
    delete truth_;
    delete without_;
    delete with_;
  }
  static std::size_t true_loops(const test::TrailedRun& run) {
    std::size_t n = 0;
    for (const LoopResult& r : run.results) n += r.detection() && truth_->is_loop(r.query, r.match);
    return n;
  }
  static std::vector<std::pair<EntryId, EntryId>> false_loops(const test::TrailedRun& run) {
    return test::false_loops(run, *truth_);
  }
  static inline GroundTruth* truth_ = nullptr;
  static inline test::TrailedRun* without_ = nullptr;
  static inline test::TrailedRun* with_ = nullptr;
};

TEST_F(Localisation, WithoutItTheImageAFewMetresBackIsAFalseLoop) {
  const LoopResult& r = without_->results[kQuery];
  ASSERT_TRUE(r.detection()) << to_string(r.status);
  EXPECT_EQ(r.match, 32u);
  EXPECT_FALSE(truth_->is_loop(kQuery, r.match));
  EXPECT_FALSE(r.localised);
  const std::vector<std::pair<EntryId, EntryId>> expected{{kQuery, 32}};
  EXPECT_EQ(false_loops(*without_), expected);
}

TEST_F(Localisation, TheLoopMovesToTheImageFromTheSamePlace) {
  const LoopResult& r = with_->results[kQuery];
  ASSERT_TRUE(r.detection()) << to_string(r.status);
  EXPECT_TRUE(r.localised);
  EXPECT_EQ(r.localised_from, 32u);
  EXPECT_TRUE(truth_->is_loop(kQuery, r.match)) << "moved to " << r.match;
  EXPECT_GE(r.match, r.island_first);
  EXPECT_LE(r.match, r.island_last);
  EXPECT_TRUE(false_loops(*with_).empty());

  // The trail holds the check of 32 and of the entry moved to, with the
  // agreement each was compared by: the image from the same place shows
  // more of the view again.
  double from = -1, to = -1;
  for (const TrailCheck& c : with_->trails[kQuery].checks) {
    if (c.entry == 32) from = c.view_agreement;
    if (c.entry == r.match) to = c.view_agreement;
  }
  EXPECT_GE(from, 0);
  EXPECT_GT(to, from);
}

TEST_F(Localisation, LosesNoTrueLoopAndMovesOnlyWithinTheIsland) {
  EXPECT_GE(true_loops(*with_), true_loops(*without_) + 1);
  std::size_t moved = 0;
  for (const LoopResult& r : with_->results) {
    if (!r.localised) continue;
    ++moved;
    EXPECT_TRUE(r.detection()) << "frame " << r.query;
    EXPECT_NE(r.localised_from, r.match) << "frame " << r.query;
    EXPECT_GE(r.match, r.island_first) << "frame " << r.query;
    EXPECT_LE(r.match, r.island_last) << "frame " << r.query;
  }
  EXPECT_GE(moved, 1u);
}

// A fit that explains most of both views is the place itself: its island's
// other images are not checked. Every loop that was checked against them
// was first accepted with a fit that explains less.
TEST_F(Localisation, AFitExplainingMostOfBothViewsIsLeftWhereItIs) {
  std::size_t left = 0, localised = 0;
  for (std::size_t i = 0; i < with_->results.size(); ++i) {
    const LoopResult& r = with_->results[i];
    if (!r.detection()) continue;
    const std::vector<TrailCheck>& checks = with_->trails[i].checks;
    const auto first_measured = std::find_if(
        checks.begin(), checks.end(), [](const TrailCheck& c) { return c.view_agreement >= 0; });
    if (first_measured == checks.end()) continue;  // an island of one candidate
    const bool checked_others = first_measured + 1 != checks.end();
    if (first_measured->view_agreement >= kViewExplained) {
      ++left;
      EXPECT_FALSE(checked_others) << "frame " << i;
      EXPECT_FALSE(r.localised) << "frame " << i;
    } else {
      localised += checked_others;
    }
  }
  EXPECT_GE(left, 1u);
  EXPECT_GE(localised, 1u);
}

}  // namespace
}  // namespace binbow::loop
