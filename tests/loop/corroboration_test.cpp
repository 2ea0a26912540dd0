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
#include "loop/detector/loop_detector_impl.h"
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

// The check of r.match that decided r (localisation may check other entries after it).
const TrailCheck& loop_check(const LoopDecisionTrail& trail, const LoopResult& r) {
  for (auto c = trail.checks.rbegin(); c != trail.checks.rend(); ++c)
    if (c->entry == r.match && c->rival_inliers == 0) return *c;
  ADD_FAILURE() << "no check of " << r.match;
  return trail.checks.back();
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
  const std::string text = describe_check(loop_check(trail, r), near_rule_of_one_frame());
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
  const std::string text = describe_check(loop_check(trail, r), params);
  EXPECT_NE(text.find("(neither within corroboration_distance 1 nor at the revisit's pace"),
            std::string::npos)
      << text;
}

// A neighbour's fit corroborates only when most of its inliers are query
// features the match's fit did not use: these are what it counts, copies of
// one corner (within vision::kDistinctInlierRadius) included.
TEST(Corroboration, SharedQueryFeaturesCountsTheNeighboursInliersOnTheMatchsFeatures) {
  const std::vector<vision::Keypoint> query = {{10, 10, 31, 0, 1, 0},   {11, 11, 31, 0, 1, 0},
                                               {100, 50, 31, 0, 1, 0},  {300, 200, 31, 0, 1, 0},
                                               {302, 200, 31, 0, 1, 0}, {500, 400, 31, 0, 1, 0}};
  const Span<vision::Keypoint> points{query.data(), query.size()};
  const std::vector<vision::Correspondence> match = {{0, 7}, {2, 8}, {3, 9}};
  // 1 is a copy of 0, 4 of 3; 5 is a feature the match's fit did not use.
  EXPECT_EQ(detail::shared_query_features(points, match, {{1, 0}, {4, 1}, {5, 2}}), 2u);
  EXPECT_EQ(detail::shared_query_features(points, match, {{5, 2}}), 0u);
  EXPECT_EQ(detail::shared_query_features(points, {}, {{0, 1}}), 0u);
  EXPECT_EQ(detail::shared_query_features(points, match, match), 3u);
}

// Every frame's result on rtabmap-samples with BRIEF and the bundled vocabulary.
std::vector<LoopResult> sample_results(const LoopDetectorParams& params) {
  LoopDetector detector(Vocabulary::load(test::source_path("data/vocab/brief_default.bbw")),
                        params);
  const auto extractor = vision::make_extractor("brief");
  vision::ImageSource source({test::samples_folder()});
  vision::Frame frame;
  std::vector<LoopResult> results;
  while (source.next(frame)) results.push_back(detector.process(extractor->extract(frame.image)));
  return results;
}

// What accepted each loop is recorded: on rtabmap-samples every loop says
// which evidence took it, and a loop with min_uncorroborated_inliers or more
// stands on its fit, which determines the fundamental matrix or a homography,
// unless the fit explains little of the views and was corroborated
// (min_uncorroborated_view_agreement).
TEST(Corroboration, EveryLoopSaysWhatAcceptedIt) {
  std::size_t loops = 0, weak = 0;
  for (const LoopResult& r : sample_results(LoopDetectorParams{})) {
    if (!r.detection()) {
      EXPECT_EQ(r.accepted_by, LoopEvidence::kNone);
      continue;
    }
    ++loops;
    EXPECT_TRUE(r.fit_evidence == vision::FitEvidence::kFundamental ||
                r.fit_evidence == vision::FitEvidence::kHomography)
        << "query " << r.query << ": " << vision::to_string(r.fit_evidence);
    if (r.inliers.size() >= 16 && !r.corroboration.view_unexplained) {
      EXPECT_EQ(r.accepted_by, LoopEvidence::kStrongFit) << "query " << r.query;
    } else {
      ++weak;
      EXPECT_NE(r.accepted_by, LoopEvidence::kStrongFit) << "query " << r.query;
      EXPECT_TRUE(r.corroboration.corroborated) << "query " << r.query;
    }
  }
  EXPECT_GE(loops, 30u);
  EXPECT_GE(weak, 1u);
  EXPECT_STREQ(to_string(LoopEvidence::kRevisitPace), "revisit-pace");
  EXPECT_STREQ(to_string(LoopEvidence::kNeighbour), "neighbour");
}

// Before temporal consistency only a fit of min_uncorroborated_inliers counts:
// a direct-index fit short of it is retried by exhaustive matching, as an
// inconsistent fit is, and the explanation measures it by that parameter.
// (k beyond the sequence: every query's check comes before the temporal test.)
TEST(Corroboration, AStrongFitIsSoughtByExhaustiveMatchingBeforeTheTemporalTest) {
  LoopDetectorParams params;
  params.k = 1000;
  LoopDetector detector(Vocabulary::load(test::source_path("data/vocab/brief_default.bbw")),
                        params);
  const auto extractor = vision::make_extractor("brief");
  vision::ImageSource source({test::samples_folder()});
  vision::Frame frame;
  std::size_t early = 0, retried = 0;
  while (source.next(frame)) {
    LoopDecisionTrail trail;
    detector.process(extractor->extract(frame.image), trail);
    for (const TrailCheck& check : trail.checks) {
      // Localisation's checks of other entries answer another question.
      if (!check.before_temporal_consistency || check.rival_inliers > 0) continue;
      ++early;
      const std::string text = describe_check(check, detector.params());
      // A strong fit explaining little of the views: min_uncorroborated_view_agreement.
      if (check.corroboration.view_unexplained) {
        EXPECT_NE(text.find("min_uncorroborated_view_agreement 0.5"), std::string::npos) << text;
        continue;
      }
      EXPECT_NE(text.find("min_uncorroborated_inliers 16"), std::string::npos)
          << "query " << trail.query << ": " << text;
      if (check.accepted()) continue;
      EXPECT_TRUE(check.exhaustive_fallback_used) << "query " << trail.query << ": " << text;
      retried += check.exhaustive_fallback_used;
    }
  }
  EXPECT_GE(early, 10u);
  EXPECT_GE(retried, 5u);
}

// With a temporal test no query can pass (k beyond the sequence), only fits
// of min_uncorroborated_inliers inliers or more are loops, each accepted on
// its own or, when it explains little of the views, with a second image;
// without strong_fits_skip_temporal_check there is none.
TEST(Corroboration, StrongFitsSkipTheTemporalTestWeakOnesDoNot) {
  LoopDetectorParams params;
  params.k = 1000;
  std::size_t loops = 0;
  for (const bool skip : {true, false}) {
    params.strong_fits_skip_temporal_check = skip;
    std::size_t found = 0;
    for (const LoopResult& r : sample_results(params)) {
      if (!r.detection()) continue;
      ++found;
      if (r.corroboration.view_unexplained)
        EXPECT_TRUE(r.corroboration.corroborated) << "query " << r.query;
      else
        EXPECT_EQ(r.accepted_by, LoopEvidence::kStrongFitAlone) << "query " << r.query;
      EXPECT_GE(r.inliers.size(), 16u) << "query " << r.query;
      EXPECT_LE(r.consistent_queries, params.k);
    }
    if (skip) {
      loops = found;
    } else {
      EXPECT_EQ(found, 0u);
    }
  }
  EXPECT_GE(loops, 20u);
}

}  // namespace
}  // namespace binbow::loop
