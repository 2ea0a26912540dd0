// Why ground-truth loops were missed: for every query that shares a place
// with an earlier image but has no true detection, what the detector made of
// that frame (its status, its best candidate, the correspondences and RANSAC
// inliers of the geometric check). What `binbow evaluate` prints under
// "missed loops:" and the report's "Missed loops" table.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/run_record.h"

namespace binbow::loop {

struct MissedLoop {
  std::size_t query = 0;
  std::string file;      // empty when not known
  std::string status;    // to_string(LoopStatus); empty when not known (no run record)
  long long match = -1;  // the frame's best candidate (or wrong loop), -1 if none
  // GT(query, match): 1 the candidate was right, 0 wrong, -1 no candidate.
  int candidate_right = -1;
  long long correspondences = -1;  // given to RANSAC; -1 not known
  long long inliers = -1;          // RANSAC inliers; -1 not known
  double normalised_score = 0;     // η of the candidate (0 when not known)
  long long features = -1;         // keypoints of the query image; -1 not known
};

// The queries with an earlier ground-truth match and no true detection, in
// frame order. `frames` is the run's per-frame outcome (LoopRun::frames,
// frame i = query i); it may be empty (only the detections are known: the
// status and candidate come from a wrong detection, or stay unknown).
// Throws InvalidArgument if a detection's index is outside the ground truth.
std::vector<MissedLoop> missed_loops(const std::vector<FrameRecord>& frames,
                                     const std::vector<Detection>& detections,
                                     const GroundTruth& truth);

// Whether the frame's candidate went through the geometric check (status
// no-geometric-consistency, or a wrong loop), so that its correspondences and
// inliers mean something; true when the status is not known.
bool geometrically_checked(const MissedLoop& miss);

// One line per miss, as `binbow evaluate` prints them under "missed loops: N":
// "  query 55: no-geometric-consistency, candidate 12 (right), 13 correspondences, 7 inliers",
// "  query 47: no-temporal-consistency, candidate 8 (right), not checked geometrically",
// each followed by ", N features" when the record knows them.
std::string format_missed_loop(const MissedLoop& miss);

}  // namespace binbow::loop
