// Why a frame ended as it did against ground truth, in sentences a user
// reads without the code: for a false loop, which tests accepted the wrong
// image and with what numbers; for a missed loop (a query with a
// ground-truth match and no true detection), the stage that stopped the true
// match — inside dislocal, not among the database results, η below α, its
// island too short or not the best, temporal consistency, or the geometric
// check — with the numbers compared ("geometric check: 9 inliers <
// min_inliers 12"). Built from the detector's LoopDecisionTrail; a true match
// the detector never checked geometrically is checked at explanation time
// with the same parameters (LoopDetector::check_pair). What the report's
// "Why" section shows.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "binbow/loop/decision_trail.h"
#include "binbow/loop/ground_truth.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/loop/run_record.h"
#include "binbow/loop/sweep.h"

namespace binbow::loop {

// One test of a geometric check: `name` `value` against the parameter's
// `threshold`, passed when value ≥ threshold. A test that is off (its
// parameter 0) is not listed.
struct CheckMeasure {
  std::string name;  // "inliers", "inlier ratio", ...
  double value = 0;
  std::string parameter;  // the LoopDetectorParams key: "min_inliers", ...
  double threshold = 0;
  bool passed = false;
  bool whole = false;  // counts: printed without decimals
  std::string note;    // what the value is a share of, "" for none
};

// The tests of `check` under `params`, in the order the check applies them:
// correspondences and inliers against min_inliers (before temporal
// consistency: min_uncorroborated_inliers, the only fit counted there), then the ratio and
// spread thresholds, whether the inliers determine the geometry
// (reject_degenerate_fits: the share of distinct points another fundamental
// matrix fits, and when that is most of them, the share another homography
// fits), then corroboration (a new FundamentalCheckResult measure is one
// more line here).
std::vector<CheckMeasure> check_measures(const TrailCheck& check, const LoopDetectorParams& params);
// "9 inliers < min_inliers 12", "inlier ratio 0.45 ≥ min_inlier_ratio 0.3".
std::string to_string(const CheckMeasure& measure);
// "20 correspondences (direct index 4, then exhaustive), 9 inliers <
// min_inliers 12: rejected" (the failed tests, or every test when it passed).
std::string describe_check(const TrailCheck& check, const LoopDetectorParams& params);

// Where a ground-truth match was lost (a miss), or that a false loop passed
// every test (kAccepted).
enum class ExplainedStage : std::uint8_t {
  kFound,                  // the query's loop was found (nothing went wrong)
  kNoGroundTruth,          // a false loop at a query without any ground-truth match
  kNoFeatures,             // the query image has no features
  kInsideDislocal,         // every ground-truth match is within dislocal of the query
  kNoDatabaseResults,      // no earlier image shares a word with the query
  kLowNormalisationScore,  // s(v_t, v_{t−Δt}) too small: the frame was skipped
  kNotAmongResults,        // no ground-truth match among the max_db_results results
  kBelowAlpha,             // the ground-truth match's η < α
  kIslandTooShort,         // its island spans fewer than min_matches_per_island
  kIslandNotChosen,        // another island scored a higher H
  kTemporalConsistency,    // its island was chosen, but the chain was too short
  kOtherEntryVerified,     // another entry of its island was checked (and failed)
  kWrongLoopAccepted,      // another entry of the chosen island passed the check
  kGeometricCheck,         // the check of the ground-truth match rejected it
};

// "found", "no ground truth", "no features", "inside dislocal", ... (the
// stage, in words).
const char* to_string(ExplainedStage stage);

// A correspondence drawn in the report: query x, y, match x, y (pixels of
// the files once explain_run has scaled them) and whether the estimator kept it.
struct ExplainedCorrespondence {
  std::array<float, 4> points{};
  bool inlier = false;
};

// At most this many correspondences are kept per explanation for the
// picture: every inlier up to half of it, rejected ones for the rest.
inline constexpr std::size_t kExplainedCorrespondences = 400;

struct LoopExplanation {
  std::size_t query = 0;
  bool false_loop = false;        // a loop was reported with an image ground truth does not match
  bool missed = false;            // the query has a ground-truth match and no true detection
  long long detected_match = -1;  // the reported loop; -1 none
  // The ground-truth match the explanation follows: the best-η one among the
  // database results, else the one whose geometric check did best; -1 none.
  long long true_match = -1;
  ExplainedStage stage = ExplainedStage::kFound;
  // One line: why the loop was accepted (false loop) and/or where the true
  // match stopped (miss), with the numbers.
  std::string reason;
  // Each stage of the pipeline in order, with its numbers.
  std::vector<std::string> steps;
  // The pair the picture shows (the false loop, else the true match) and its
  // check: the detector's, or run for the explanation (check_rerun).
  long long drawn_match = -1;
  bool has_check = false;
  bool check_rerun = false;
  std::vector<CheckMeasure> measures;  // check_measures() of it
  std::size_t check_correspondences = 0, check_inliers = 0;
  // Its correspondences for the picture, at most kExplainedCorrespondences
  // (explain_run keeps them for the pictured cases only).
  std::vector<ExplainedCorrespondence> correspondences;
  std::string query_file, match_file;  // of the drawn pair, when known
};

// Explains frame `trail.query` against `truth` (frames beyond it have no
// ground-truth match). `detector` (optional) is the one that produced the
// trail, right after that query: it re-checks a ground-truth match it never
// verified and supplies the keypoints of the drawn correspondences (in the
// detector's pixels).
LoopExplanation explain_frame(const LoopDecisionTrail& trail, const GroundTruth& truth,
                              const LoopDetectorParams& params,
                              const LoopDetector* detector = nullptr);

struct RunExplanations {
  // Every false loop and every miss, in frame order. The first `pictured`
  // keep their files and correspondences for a picture; the others only their text.
  std::vector<LoopExplanation> cases;
  std::size_t pictured = 0;
  // Empty, or what differs between the re-run and the record (the
  // explanations describe the re-run).
  std::string note;
};

// explain_run re-checks ground-truth matches (and keeps correspondences) for
// this many cases at most; later ones are explained from the trail alone.
inline constexpr std::size_t kMaxRecheckedCases = 500;

// Re-runs the recorded run's detection over its features (as
// sweep_parameter does, with the run's parameters), recording each frame's
// trail, and explains every false loop and every miss against `truth`. At
// most `max_pictured` cases keep their correspondences (in pixels of the
// files). `vocabulary` is unused for an online run. Errors as sweep_parameter.
RunExplanations explain_run(const LoopRun& run, const RunFeatures& features,
                            const Vocabulary& vocabulary, const GroundTruth& truth,
                            std::size_t max_pictured, const SweepProgress& progress = {});

}  // namespace binbow::loop
