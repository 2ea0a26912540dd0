// How a loop with few inliers was corroborated (LoopDetectorParams::
// min_uncorroborated_inliers), as LoopResult and the decision trail report it.
#pragma once

#include <cstddef>
#include <cstdint>

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
struct LoopCorroboration {
  bool needed = false;
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
  kNearPreviousLoop,  // a weak fit near the latest loop (corroboration_distance)
  kRevisitPace,       // a weak fit at the revisit's pace since the latest loop
  kNeighbour,         // a weak fit that a neighbour of the match corroborates with other features
};

// "none", "unchecked", "strong-fit", "strong-fit-alone", "near-previous-loop",
// "revisit-pace", "neighbour".
const char* to_string(LoopEvidence evidence);

}  // namespace binbow::loop
