// Why false loops were accepted: for every detection the ground truth does
// not hold, what accepted it (a strong fit, a weak one corroborated by the
// latest loop or by a neighbour, ...: LoopEvidence), from the run record.
// What `binbow evaluate` prints under "false loops:".
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/run_record.h"

namespace binbow::loop {

struct FalseLoop {
  std::size_t query = 0;
  std::size_t match = 0;
  std::string file;  // the query's image; empty when not known
  std::size_t inliers = 0;
  double score = 0;
  // to_string(LoopEvidence) of what accepted it; empty when not known (no
  // run record, or one written before it kept the evidence).
  std::string accepted_by;
  // The island entry localisation moved the loop from, -1 if it did not
  // move it or it is not known.
  long long localised_from = -1;
};

// The detections that are not ground-truth loops, in the order of
// `detections`. `frames` is the run's per-frame outcome (LoopRun::frames,
// frame i = query i); it may be empty (the evidence is then not known).
// Throws InvalidArgument if a detection's index is outside the ground truth.
std::vector<FalseLoop> false_loops(const std::vector<FrameRecord>& frames,
                                   const std::vector<Detection>& detections,
                                   const GroundTruth& truth);

// One line per false loop, as `binbow evaluate` prints them under
// "false loops: N":
// "  query 60: match 23, 15 inliers, accepted by revisit-pace",
// "  query 66: match 33, 18 inliers, accepted by strong-fit, localised from 31",
// "  query 9: match 8, 20 inliers, evidence unknown".
std::string format_false_loop(const FalseLoop& loop);

}  // namespace binbow::loop
