// How a loop with a weak fit was corroborated (LoopDetectorParams::
// min_uncorroborated_inliers, min_uncorroborated_view_agreement), as
// LoopResult and the decision trail report it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "binbow/types.h"

namespace binbow::loop {

// The corroboration of a loop with fewer than min_uncorroborated_inliers
// inliers (LoopDetectorParams): whether it was needed; the detector's latest
// loop before this query (if any: its query and match, and whether it
// corroborated only by the revisit's pace, beyond corroboration_distance);
// whether a neighbour of the match was checked, the one with the most
// inliers, their number and how many of them are query features the
// match's inliers already use (within vision::kDistinctInlierRadius); and
// whether either corroborated the loop. A neighbour corroborates only with
// a consistent, non-degenerate fit of its own that rests mostly on other
// features of the query: the neighbouring frame sees what the match sees, so
// a fit on the same query features repeats the match's evidence (a
// repeated structure fits both alike) instead of adding to it.
//
// A fit of min_uncorroborated_inliers inliers or more needs corroboration
// too when it explains less of the two views than
// min_uncorroborated_view_agreement (view_unexplained; the agreement is the
// trail's TrailCheck::view_agreement), before or after the temporal test.
// Its neighbour corroborates with any consistent, non-degenerate fit: what
// it must show is a second viewpoint on the place, not other features.
struct LoopCorroboration {
  bool needed = false;
  bool view_unexplained = false;
  bool has_previous_loop = false;
  EntryId previous_loop_query = 0;
  EntryId previous_loop_match = 0;
  bool previous_loop_at_pace = false;
  bool neighbour_checked = false;
  EntryId corroborating_neighbour = 0;
  std::size_t neighbour_inliers = 0;
  std::size_t neighbour_shared_inliers = 0;
  bool corroborated = false;
};

// What accepted a loop (LoopResult::accepted_by).
enum class LoopEvidence : std::uint8_t {
  kNone,       // no loop
  kUnchecked,  // geometric_check "none": the temporal rules alone
  kStrongFit,  // a fit with min_uncorroborated_inliers inliers or more (or the rule off)
  // Such a fit before the temporal test passed (strong_fits_skip_temporal_check).
  kStrongFitAlone,
  // A weak fit (few inliers, or explaining little of the views), corroborated:
  kNearPreviousLoop,  // near the latest loop (corroboration_distance)
  kRevisitPace,       // at the revisit's pace since the latest loop
  kNeighbour,         // by a neighbour of the match (on other features, when short of inliers)
};

// "none", "unchecked", "strong-fit", "strong-fit-alone", "near-previous-loop",
// "revisit-pace", "neighbour".
const char* to_string(LoopEvidence evidence);
// The evidence of that name; false (and *evidence untouched) for any other.
bool parse_loop_evidence(const std::string& name, LoopEvidence* evidence);

}  // namespace binbow::loop
