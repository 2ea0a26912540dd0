// The corroboration of weak loops (LoopDetectorParams::
// min_uncorroborated_inliers) on rtabmap-samples with BRIEF and the bundled
// vocabulary: query 59 fits frame 19 with 13 inliers, two queries after the
// loop 57 → 17, and no neighbour of frame 19 fits the query. With
// corroboration_distance 1 the near-loop rule cannot take it, so whether it
// is a loop is decided by the revisit's pace alone.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "binbow/loop/explanation.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

using vision::Features;

// Query 59's result and trail, after frames 0–58, with `params`.
LoopResult query_59(const LoopDetectorParams& params, LoopDecisionTrail& trail) {
  const std::string vocabulary = test::source_path("data/vocab/brief_default.bbw");
  EXPECT_TRUE(std::filesystem::exists(vocabulary)) << vocabulary << " is missing";
  LoopDetector detector(Vocabulary::load(vocabulary), params);
  const auto extractor = vision::make_extractor("brief");
  vision::ImageSource source({test::samples_folder()});
  vision::Frame frame;
  for (int i = 0; i < 59; ++i) {
    EXPECT_TRUE(source.next(frame));
    detector.process(extractor->extract(frame.image));
  }
  EXPECT_TRUE(source.next(frame));
  return detector.process(extractor->extract(frame.image), trail);
}

LoopDetectorParams near_rule_of_one_frame() {
  LoopDetectorParams params;
  params.corroboration_distance = 1;
  return params;
}

TEST(Corroboration, TheRevisitsPaceCorroboratesAWeakLoopTheNearRuleDoesNot) {
  LoopDecisionTrail trail;
  const LoopResult r = query_59(near_rule_of_one_frame(), trail);
  ASSERT_TRUE(r.detection()) << to_string(r.status);
  EXPECT_EQ(r.match, 19u);
  EXPECT_LT(r.inliers.size(), 16u);
  const LoopCorroboration& c = r.corroboration;
  EXPECT_TRUE(c.needed);
  EXPECT_TRUE(c.has_previous_loop);
  EXPECT_EQ(c.previous_loop_query, 57u);
  EXPECT_EQ(c.previous_loop_match, 17u);
  EXPECT_TRUE(c.previous_loop_at_pace);
  EXPECT_FALSE(c.neighbour_checked);
  EXPECT_TRUE(c.corroborated);
  ASSERT_FALSE(trail.checks.empty());
  const std::string text = describe_check(trail.checks.back(), near_rule_of_one_frame());
  EXPECT_NE(text.find("corroborated: the latest loop was 57 → 17 (at the revisit's pace"),
            std::string::npos)
      << text;
}

TEST(Corroboration, WithoutThePaceRuleTheSameWeakLoopIsRejected) {
  LoopDetectorParams params = near_rule_of_one_frame();
  params.corroboration_horizon = 1;  // the pace rule then adds nothing to the near rule
  LoopDecisionTrail trail;
  const LoopResult r = query_59(params, trail);
  EXPECT_FALSE(r.detection());
  EXPECT_EQ(r.status, LoopStatus::kNoGeometricConsistency);
  EXPECT_EQ(r.match, 19u);
  EXPECT_TRUE(r.corroboration.needed);
  EXPECT_FALSE(r.corroboration.previous_loop_at_pace);
  EXPECT_TRUE(r.corroboration.neighbour_checked);
  EXPECT_FALSE(r.corroboration.corroborated);
  ASSERT_FALSE(trail.checks.empty());
  const std::string text = describe_check(trail.checks.back(), params);
  EXPECT_NE(text.find("(neither within corroboration_distance 1 nor at the revisit's pace"),
            std::string::npos)
      << text;
}

}  // namespace
}  // namespace binbow::loop
