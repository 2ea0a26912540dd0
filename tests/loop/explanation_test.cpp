// Explanations of false loops and misses: the stage named for constructed
// decision trails, the trail the detector records on real images, and the
// report's "Why" section through the CLI (rendered in headless Chromium).
#include "binbow/loop/explanation.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "binbow/loop/report.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

using vision::Correspondence;

// A trail of query 40 that went through every stage: candidates 11–14 (η
// 0.8 at 12) and 2 (η 0.2), island 11–14 chosen, a temporal chain of 4 queries,
// and one check of 12 with 20 correspondences and `inliers` inliers.
LoopDecisionTrail full_trail(std::size_t inliers, bool consistent) {
  LoopDecisionTrail t;
  t.query = 40;
  t.features = 500;
  t.queried = true;
  t.newest_candidate = 19;
  t.normalisation_score = 0.1;
  t.candidates = {
      {12, 0.08, 0.8}, {13, 0.06, 0.6}, {11, 0.05, 0.5}, {14, 0.04, 0.4}, {2, 0.02, 0.2}};
  t.islands = {{11, 14, 2.3, 12, 0.8, true}};
  t.chosen_island = 0;
  t.temporal_tested = true;
  t.temporal = {3, 38, 39, 10, 13, 0, 4};
  TrailCheck check;
  check.entry = 12;
  check.normalised_score = 0.8;
  check.direct_index_correspondences = 20;
  for (std::uint32_t i = 0; i < 20; ++i) check.correspondences.push_back({i, i});
  check.fit.inliers.assign(check.correspondences.begin(),
                           check.correspondences.begin() + static_cast<long>(inliers));
  check.fit.inlier_ratio = double(inliers) / 20;
  check.fit.consistent = consistent;
  t.checks = {check};
  t.status = consistent ? LoopStatus::kLoopDetected : LoopStatus::kNoGeometricConsistency;
  t.match = 12;
  return t;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(Explanation, MissRejectedByTheGeometricCheckNamesTheNumbers) {
  const GroundTruth truth(50, {{40, 12}, {40, 13}});
  const LoopExplanation e = explain_frame(full_trail(9, false), truth, LoopDetectorParams{});
  EXPECT_TRUE(e.missed);
  EXPECT_FALSE(e.false_loop);
  EXPECT_EQ(e.stage, ExplainedStage::kGeometricCheck);
  EXPECT_EQ(e.true_match, 12);
  EXPECT_TRUE(contains(e.reason, "9 inliers < min_inliers 12")) << e.reason;
  EXPECT_TRUE(e.has_check);
  EXPECT_FALSE(e.check_rerun);
  EXPECT_EQ(e.check_inliers, 9u);
  EXPECT_EQ(e.check_correspondences, 20u);
  // Every stage before it passed, with its numbers.
  std::string steps;
  for (const std::string& s : e.steps) steps += s + "\n";
  EXPECT_TRUE(contains(steps, "ground-truth match 12: result 1 of 5, η 0.8 ≥ α 0.3")) << steps;
  EXPECT_TRUE(contains(steps, "11–14 (H 2.3) chosen")) << steps;
  EXPECT_TRUE(contains(steps, "temporal consistency 3 ≥ k 3")) << steps;
}

TEST(Explanation, InlierRatioBelowItsThresholdIsTheReason) {
  const GroundTruth truth(50, {{40, 12}});
  LoopDetectorParams params;
  params.min_inliers = 8;
  params.min_inlier_ratio = 0.5;
  const LoopExplanation e = explain_frame(full_trail(9, false), truth, params);
  EXPECT_EQ(e.stage, ExplainedStage::kGeometricCheck);
  EXPECT_TRUE(contains(e.reason, "inlier ratio 0.45 < min_inlier_ratio 0.5")) << e.reason;
  EXPECT_FALSE(contains(e.reason, "9 inliers <")) << e.reason;  // that test passed
  ASSERT_EQ(e.measures.size(), 3u);
  EXPECT_EQ(e.measures[2].parameter, "min_inlier_ratio");
  EXPECT_FALSE(e.measures[2].passed);
}

TEST(Explanation, MissWhoseMatchWasNeverACandidate) {
  // Ground truth: image 5, which the database did not return.
  const GroundTruth truth(50, {{40, 5}});
  ASSERT_EQ(full_trail(9, false).candidates.size(), 5u);
  const LoopExplanation e = explain_frame(full_trail(9, false), truth, LoopDetectorParams{});
  EXPECT_TRUE(e.missed);
  EXPECT_EQ(e.stage, ExplainedStage::kNotAmongResults);
  EXPECT_TRUE(contains(e.reason, "no ground-truth match (5) among the 5 database results"))
      << e.reason;
  EXPECT_FALSE(e.has_check);  // no detector to re-check with
}

TEST(Explanation, MissBelowAlpha) {
  const GroundTruth truth(50, {{40, 2}});
  const LoopExplanation e = explain_frame(full_trail(9, false), truth, LoopDetectorParams{});
  EXPECT_EQ(e.stage, ExplainedStage::kBelowAlpha);
  EXPECT_EQ(e.true_match, 2);
  EXPECT_TRUE(contains(e.reason, "ground-truth match 2: η 0.2 < α 0.3")) << e.reason;
}

TEST(Explanation, MissInsideDislocal) {
  const GroundTruth truth(50, {{40, 25}});
  const LoopExplanation e = explain_frame(full_trail(9, false), truth, LoopDetectorParams{});
  EXPECT_EQ(e.stage, ExplainedStage::kInsideDislocal);
  EXPECT_TRUE(contains(e.reason, "within dislocal 20")) << e.reason;
}

TEST(Explanation, MissWhoseIslandLostOrWasTooShort) {
  LoopDecisionTrail t = full_trail(9, false);
  t.candidates.push_back({3, 0.03, 0.35});
  t.islands = {{3, 3, 0.35, 3, 0.35, true}, {11, 14, 2.3, 12, 0.8, true}};
  t.chosen_island = 1;
  const GroundTruth truth(50, {{40, 3}});
  LoopExplanation e = explain_frame(t, truth, LoopDetectorParams{});
  EXPECT_EQ(e.stage, ExplainedStage::kIslandNotChosen);
  EXPECT_TRUE(
      contains(e.reason, "its island 3 (H 0.35) scores below the chosen island 11–14 (H 2.3)"))
      << e.reason;
  t.islands[0].long_enough = false;
  LoopDetectorParams params;
  params.min_matches_per_island = 2;
  e = explain_frame(t, truth, params);
  EXPECT_EQ(e.stage, ExplainedStage::kIslandTooShort);
  EXPECT_TRUE(contains(e.reason, "spans 1 < min_matches_per_island 2")) << e.reason;
}

TEST(Explanation, MissStoppedByTemporalConsistencySaysWhyTheChainRestarted) {
  LoopDecisionTrail t = full_trail(9, false);
  t.checks.clear();
  t.status = LoopStatus::kNoTemporalConsistency;
  t.temporal = {3, 38, 39, 30, 33, 16, 1};  // the previous island 30–33 is 16 entries away
  const GroundTruth truth(50, {{40, 12}});
  const LoopExplanation e = explain_frame(t, truth, LoopDetectorParams{});
  EXPECT_EQ(e.stage, ExplainedStage::kTemporalConsistency);
  EXPECT_TRUE(contains(e.reason, "temporal consistency 0 < k 3")) << e.reason;
  EXPECT_TRUE(contains(e.reason,
                       "16 entries from the previous query's island 30–33 > "
                       "max_distance_between_islands 3"))
      << e.reason;
}

TEST(Explanation, FalseLoopSaysWhatAcceptedIt) {
  const GroundTruth truth(50, {{20, 3}});  // nothing at query 40
  const LoopExplanation e = explain_frame(full_trail(14, true), truth, LoopDetectorParams{});
  EXPECT_TRUE(e.false_loop);
  EXPECT_FALSE(e.missed);
  EXPECT_EQ(e.stage, ExplainedStage::kNoGroundTruth);
  EXPECT_EQ(e.detected_match, 12);
  EXPECT_EQ(e.drawn_match, 12);
  EXPECT_TRUE(contains(e.reason, "false loop with 12")) << e.reason;
  EXPECT_TRUE(contains(e.reason, "temporal consistency 3 ≥ k 3")) << e.reason;
  EXPECT_TRUE(contains(e.reason,
                       "accepted (20 correspondences ≥ min_inliers 12, 14 inliers ≥ "
                       "min_inliers 12)"))
      << e.reason;
}

// A fit of 13 inliers needs corroboration: the text names the rule that
// gave it (near the latest loop, at the revisit's pace since it) or that
// both failed.
TEST(Explanation, WeakLoopSaysWhatCorroboratedIt) {
  TrailCheck check = full_trail(13, true).checks.front();
  check.corroboration.needed = true;
  check.corroboration.has_previous_loop = true;
  check.corroboration.previous_loop_query = 35;
  check.corroboration.previous_loop_match = 7;
  check.corroboration.previous_loop_at_pace = true;
  check.corroboration.corroborated = true;
  const LoopDetectorParams params;
  std::string text = describe_check(check, params);
  EXPECT_TRUE(contains(text,
                       "13 inliers < min_uncorroborated_inliers 16, corroborated: the "
                       "latest loop was 35 → 7 (at the revisit's pace: "
                       "corroboration_horizon 10, corroboration_pace_tolerance 0.25)"))
      << text;
  check.corroboration.previous_loop_at_pace = false;
  text = describe_check(check, params);
  EXPECT_TRUE(contains(text, "latest loop was 35 → 7 (within corroboration_distance 4)")) << text;
  check.corroboration.corroborated = false;
  check.corroboration.neighbour_checked = true;
  check.corroboration.corroborating_neighbour = 11;
  text = describe_check(check, params);
  EXPECT_TRUE(contains(text,
                       "rejected: 13 inliers < min_uncorroborated_inliers 16 and not corroborated "
                       "(the latest loop was 35 → 7 (neither within corroboration_distance 4 nor "
                       "at the revisit's pace: corroboration_horizon 10, "
                       "corroboration_pace_tolerance 0.25); the best neighbour of the match, 11, "
                       "has 0 inliers, 0 on query features the match's inliers use)"))
      << text;
}

TEST(Explanation, WrongLoopIsBothFalseAndMissed) {
  // The true place is 3, whose island lost; 12 was accepted.
  LoopDecisionTrail t = full_trail(14, true);
  t.candidates.push_back({3, 0.03, 0.35});
  t.islands = {{3, 3, 0.35, 3, 0.35, true}, {11, 14, 2.3, 12, 0.8, true}};
  t.chosen_island = 1;
  const GroundTruth truth(50, {{40, 3}});
  const LoopExplanation e = explain_frame(t, truth, LoopDetectorParams{});
  EXPECT_TRUE(e.false_loop);
  EXPECT_TRUE(e.missed);
  EXPECT_EQ(e.stage, ExplainedStage::kIslandNotChosen);
  EXPECT_TRUE(contains(e.reason, "false loop with 12")) << e.reason;
  EXPECT_TRUE(contains(e.reason, "ground-truth match 3: its island")) << e.reason;
}

TEST(Explanation, ReportDrawsTheFirstCasesAndListsEveryOne) {
  LoopReport report;
  report.title = "explained";
  report.has_result = true;
  report.has_explanations = true;
  const GroundTruth truth(50, {{40, 12}});
  for (std::size_t i = 0; i < kExplainedPictures + 5; ++i) {
    LoopExplanation e = explain_frame(full_trail(9, false), truth, LoopDetectorParams{});
    e.query = i;
    report.explanations.push_back(e);
  }
  test::TempDir dir;
  std::ifstream in(write_loop_report(dir.path(), report));
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string page = buffer.str();
  const auto count = [&](const std::string& pattern) {
    const std::regex expression(pattern);
    return std::distance(std::sregex_iterator(page.begin(), page.end(), expression),
                         std::sregex_iterator());
  };
  EXPECT_EQ(count("<tr id='explain-row-\\d+'>"), long(kExplainedPictures + 5));
  EXPECT_EQ(count("<figure class='explain'"), long(kExplainedPictures));
  EXPECT_TRUE(contains(page, "are listed in the table only"));
  EXPECT_TRUE(contains(page, "9 inliers &lt; min_inliers 12"));
  // The check's tests as a table: failed ones marked.
  EXPECT_TRUE(contains(page,
                       "<tr><td>inliers</td><td class='n'>9</td><td>min_inliers</td><td "
                       "class='n'>12</td><td><span class='fp'>failed</span></td></tr>"));
}

// The features of rtabmap-samples with the bundled ORB vocabulary.
struct Sequence {
  Vocabulary vocabulary = Vocabulary::load(test::source_path("data/vocab/orb_default.bbw"));
  std::vector<vision::Features> frames;
  Sequence() {
    const auto extractor = vision::make_extractor("orb");
    vision::ImageSource source({test::shared_data("rtabmap-samples/samples")});
    vision::Frame frame;
    while (source.next(frame)) frames.push_back(extractor->extract(frame.image));
  }
};

TEST(DecisionTrail, RecordsWithoutChangingResultsAndCheckPairRepeatsTheCheck) {
  const Sequence s;
  ASSERT_EQ(s.frames.size(), 84u);
  LoopDetectorParams params;
  params.min_inliers = 8;  // provokes false loops, so that every stage is reached
  LoopDetector plain(s.vocabulary, params), recording(s.vocabulary, params);
  LoopDecisionTrail trail;
  std::size_t checked = 0;
  for (const vision::Features& f : s.frames) {
    const LoopResult a = plain.process(f);
    const LoopResult b = recording.process(f, trail);
    ASSERT_EQ(a.status, b.status) << a.query;
    ASSERT_EQ(a.match, b.match) << a.query;
    ASSERT_EQ(a.inliers, b.inliers) << a.query;
    ASSERT_EQ(trail.query, a.query);
    ASSERT_EQ(trail.status, a.status);
    ASSERT_EQ(trail.queried, a.query > 20u);
    if (a.status == LoopStatus::kNoDatabaseResults) continue;
    ASSERT_FALSE(trail.candidates.empty()) << a.query;
    for (std::size_t i = 1; i < trail.candidates.size(); ++i)
      ASSERT_GE(trail.candidates[i - 1].score, trail.candidates[i].score) << a.query;
    if (a.status == LoopStatus::kNoGeometricConsistency || a.detection()) {
      // One check; after a detection, localisation's checks of the island's
      // other entries may follow, and the loop is the accepted one of them.
      ASSERT_GE(trail.checks.size(), 1u) << a.query;
      if (!a.detection()) {
        ASSERT_EQ(trail.checks.size(), 1u) << a.query;
      }
      if (!a.localised) {
        EXPECT_EQ(trail.checks.front().entry, a.match) << a.query;
      }
      const auto decided = std::find_if(
          trail.checks.rbegin(), trail.checks.rend(),
          [&](const TrailCheck& t) { return t.entry == a.match && t.accepted() == a.detection(); });
      ASSERT_NE(decided, trail.checks.rend()) << a.query;
      const TrailCheck& c = *decided;
      EXPECT_EQ(c.entry, a.match);
      EXPECT_EQ(c.correspondences.size(), a.correspondences);
      EXPECT_EQ(c.fit.inliers, a.inliers);
      EXPECT_EQ(c.accepted(), a.detection());
      ASSERT_GE(trail.chosen_island, 0);
      EXPECT_EQ(trail.temporal.chain_after, a.consistent_queries);
      // The same check, run again for the pair.
      const TrailCheck again = recording.check_pair(a.query, a.match);
      EXPECT_EQ(again.correspondences, c.correspondences) << a.query;
      EXPECT_EQ(again.fit.inliers, c.fit.inliers) << a.query;
      ++checked;
    }
  }
  EXPECT_GT(checked, 30u);
}

TEST(DecisionTrail, ReportExplainsFalseLoopsAndMissesThroughTheCommandLine) {
  test::TempDir dir;
  const std::string csv = dir.file("loops.csv"), report = dir.file("report");
  std::string out;
  // min_inliers 8 without corroboration and with degenerate fits lets a
  // false loop through; 3 database results lose true matches to islands and
  // temporal consistency.
  ASSERT_EQ(
      test::run_cli("detect-loops --vocab " + test::source_path("data/vocab/orb_default.bbw") +
                        " --min-inliers 8 --min-uncorroborated-inliers 0"
                        " --reject-degenerate-fits false --max-db-results 3 -o " +
                        csv + " " + test::shared_data("rtabmap-samples/samples"),
                    &out),
      0)
      << out;
  ASSERT_EQ(test::run_cli("evaluate --gt " + test::shared_data("rtabmap-samples/samples_GT.bmp") +
                              " --report " + report + " " + csv,
                          &out),
            0)
      << out;
  const double false_positives = test::printed_number(out, "false positives");
  const double missed = test::printed_number(out, "missed loops");
  ASSERT_GT(false_positives, 0) << out;
  ASSERT_GT(missed, 0) << out;
  std::ifstream in(report + "/index.html");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string page = buffer.str();
  ASSERT_TRUE(contains(page, "<h2 id='explained'>")) << out;
  EXPECT_FALSE(contains(page, "re-running detection gave")) << "the re-run differs from the run";
  // One row per false loop and per miss; a false loop names the check that accepted it.
  const std::regex row("<tr id='explain-row-\\d+'>");
  const auto rows = std::distance(std::sregex_iterator(page.begin(), page.end(), row), {});
  EXPECT_GE(double(rows), missed);
  EXPECT_LE(double(rows), missed + false_positives);
  EXPECT_TRUE(contains(page, "accepted by the geometric check")) << "no false loop explained";
  EXPECT_TRUE(contains(page, "inliers ≥ min_inliers 8"));
  EXPECT_TRUE(
      std::regex_search(page, std::regex("temporal consistency [0-2] &lt; k 3 \\(consistent "
                                         "queries before this one; chain restarted")));
  EXPECT_TRUE(std::regex_search(
      page, std::regex("<td class='s'>island not chosen</td><td>ground-truth match \\d+: its "
                       "island [^<]* scores below the chosen island")));
  // Query 58's true match 17 gives no correspondence that passes the ratio test.
  EXPECT_TRUE(contains(page, "geometric check of ground-truth match 17: 0 correspondences"));
  // A true match the detector never checked (its chain was too short) is checked for the report.
  EXPECT_TRUE(contains(page, "been checked (run for this explanation, same parameters)"));
  EXPECT_TRUE(contains(page, "this check was run for the report with the run's parameters"));
  // Pictures: a figure with the two images per case.
  const std::size_t figure = page.find("<figure class='explain' id='explain-58'>");
  ASSERT_NE(figure, std::string::npos);
  const std::size_t image =
      page.find("<img alt='query 58 and image 17' src='data:image/jpeg;base64,", figure);
  EXPECT_LT(image, page.find("</figure>", figure));
  const std::string screenshot = dir.file("explained.png");
  ASSERT_TRUE(test::render_in_chromium(report + "/index.html", screenshot, dir.path()));
  EXPECT_GT(std::filesystem::file_size(screenshot), 20000u);
}

}  // namespace
}  // namespace binbow::loop
