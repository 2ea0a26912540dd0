// What the loop detector saw and decided for one query, stage by stage, with
// the numbers each test compared: every database result and its η, every
// island (the ones too short included), the temporal chain before and after
// the query, and every geometric check with its correspondences and the
// estimator's outcome. LoopDetector::process(features, trail) fills it; the
// plain process() records nothing, so detection pays nothing for it.
// explanation.h turns a trail into the sentences of the report ("geometric
// check: 9 inliers < min_inliers 12").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "binbow/loop/corroboration.h"
#include "binbow/types.h"
#include "binbow/vision/geometric_check.h"

namespace binbow::loop {

struct LoopDetectorParams;

enum class LoopStatus : std::uint8_t;

// One database result of the query (pipeline stage 2), whether or not it
// reached α.
struct TrailCandidate {
  EntryId entry = 0;
  double score = 0;             // s(v_t, v_entry)
  double normalised_score = 0;  // η = score / s(v_t, v_{t−Δt}) (= score without normalisation)
};

// A run of candidates reaching α with nearby entry ids (stage 4). The trail
// keeps the islands shorter than min_matches_per_island too, which the
// detector drops, so that a reader sees why a candidate's island never
// competed.
struct TrailIsland {
  EntryId first = 0, last = 0;
  double score = 0;  // H = Σ η of its candidates
  EntryId best_entry = 0;
  double best_score = 0;    // η of best_entry
  bool long_enough = true;  // last − first + 1 ≥ min_matches_per_island
};

// The temporal-consistency test (stage 5) for the chosen island. Query
// positions are on the detector's time axis: images with features when
// skip_featureless_frames is on, entry ids otherwise.
struct TrailTemporal {
  int chain_before = 0;  // consistent queries before this one (0: no chain)
  // Positions of the previous query that had an island and of this one; the
  // chain restarts when they are more than max_distance_between_queries apart.
  EntryId previous_query = 0, query = 0;
  EntryId previous_first = 0, previous_last = 0;  // the previous query's island
  // Entries between the previous island and this one (≤ 0: they overlap or
  // touch); the chain restarts when it exceeds max_distance_between_islands.
  long long island_gap = 0;
  int chain_after = 0;  // LoopResult::consistent_queries: this query included
};

// One geometric check (stage 6) of the query against `entry`.
struct TrailCheck {
  EntryId entry = 0;
  double normalised_score = 0;  // η of entry (0 for a check run outside detection)
  // With GeometricCheck::kDirectIndex: the direct index's correspondences,
  // before an exhaustive fallback replaced them; -1 when it was not used.
  long long direct_index_correspondences = -1;
  bool exhaustive_fallback_used = false;
  // What the estimator was given (the last attempt's) and what it made of
  // them: consistent, inliers (a subset of correspondences), inlier ratio,
  // spread, and whatever measures FundamentalCheckResult gains.
  std::vector<vision::Correspondence> correspondences;
  vision::FundamentalCheckResult fit;
  // A consistent fit with fewer than min_uncorroborated_inliers inliers
  // needs corroboration, as in LoopResult. Not evaluated for checks run
  // outside detection (LoopDetector::check_pair).
  LoopCorroboration corroboration;
  // Run before the temporal test passed (strong_fits_skip_temporal_check):
  // the fit itself then needs min_uncorroborated_inliers inliers (where it
  // otherwise needs min_inliers) to be consistent, so it needs no
  // corroboration, and nothing corroborates a weaker one.
  bool before_temporal_consistency = false;
  // A localisation check (LoopDetectorParams::localise_in_island): the
  // inliers of the accepted fit it had to exceed (0 for any other check).
  // Such a check matches through the direct index only.
  std::size_t rival_inliers = 0;
  // vision::view_agreement() of the fit, measured for the accepted fit and
  // the checks that localisation compares with it; -1 when not measured.
  double view_agreement = -1;

  // The inliers the check asked of its fit under `params`: min_inliers;
  // before temporal consistency at least min_uncorroborated_inliers; in
  // localisation more than rival_inliers. The detector asks it and the
  // explanations measure by it.
  int inliers_asked(const LoopDetectorParams& params) const;

  // Whether the check let the entry through: a consistent fit, corroborated when needed.
  bool accepted() const noexcept {
    return fit.consistent && (!corroboration.needed || corroboration.corroborated);
  }
};

struct LoopDecisionTrail {
  EntryId query = 0;
  LoopStatus status{};
  std::size_t features = 0;
  // Whether the database was queried: the query has entries older than
  // dislocal (query > dislocal). Candidates are entries ≤ newest_candidate.
  bool queried = false;
  EntryId newest_candidate = 0;
  double normalisation_score = 0;  // s(v_t, v_{t−Δt}); 0 when not computed
  // Every database result (at most max_db_results), best score first.
  std::vector<TrailCandidate> candidates;
  // The islands of the candidates reaching α, in entry order, short ones included.
  std::vector<TrailIsland> islands;
  int chosen_island = -1;  // index into islands; -1: none was chosen
  bool temporal_tested = false;
  TrailTemporal temporal;
  // The checks run, in order: the island's best entry, then its other
  // entries (max_verified_entries), then localisation's (localise_in_island).
  // Empty when no candidate got this far or with GeometricCheck::kNone.
  std::vector<TrailCheck> checks;
  long long match = -1;  // LoopResult::match: the loop, or the best candidate; -1 none

  // The last check that accepted `entry`; for the loop's match, the check
  // that accepted the loop (localisation checks of other entries may follow
  // it). Null when no check accepted it.
  const TrailCheck* accepted_check(EntryId entry) const;
  TrailCheck* accepted_check(EntryId entry);
};

}  // namespace binbow::loop
