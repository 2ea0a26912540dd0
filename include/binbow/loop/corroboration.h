// How a loop with few inliers was corroborated (LoopDetectorParams::
// min_uncorroborated_inliers), as LoopResult and the decision trail report it.
#pragma once

#include <cstddef>

#include "binbow/types.h"

namespace binbow::loop {

// The corroboration of a loop with fewer than min_uncorroborated_inliers
// inliers (LoopDetectorParams): whether it was needed; the detector's latest
// loop before this query (if any: its query and match, and whether it
// corroborated only by the revisit's pace, beyond corroboration_distance);
// whether a neighbour of the match was checked, the one with the most
// inliers and their number; and whether either corroborated the loop.
struct LoopCorroboration {
  bool needed = false;
  bool has_previous_loop = false;
  EntryId previous_loop_query = 0;
  EntryId previous_loop_match = 0;
  bool previous_loop_at_pace = false;
  bool neighbour_checked = false;
  EntryId corroborating_neighbour = 0;
  std::size_t neighbour_inliers = 0;
  bool corroborated = false;
};

}  // namespace binbow::loop
