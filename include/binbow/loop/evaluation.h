// Evaluating loop detection against ground truth: the paper's precision and
// recall of detections (loops_csv.h) against a ground truth (ground_truth.h).
#pragma once

#include <cstddef>
#include <vector>

#include "binbow/loop/ground_truth.h"
#include "binbow/loop/loops_csv.h"

namespace binbow::loop {

// The paper's measures: a detection at query i is a true positive when
// ground truth has (i, match); precision = true positives / detections (1
// when nothing is detected: no false alarm was raised); recall = queries with
// a true positive / queries that have any ground-truth loop.
struct PrecisionRecall {
  std::size_t detections = 0;
  std::size_t true_positives = 0;
  std::size_t false_positives = 0;
  std::size_t queries_with_loops = 0;
  std::size_t queries_found = 0;  // distinct queries with a true positive
  double precision = 1;
  double recall = 0;
};

// Throws InvalidArgument naming the detection if its query or match is not
// a frame of the ground truth (what every measure of detections checks first).
void check_detection_inside(const Detection& detection, const GroundTruth& truth);

// Throws InvalidArgument if a detection's index is outside the ground truth.
// O(detections × log) time, memory linear in the detections.
PrecisionRecall evaluate_detections(const std::vector<Detection>& detections,
                                    const GroundTruth& truth);

// A point of a precision–recall curve: the value of the swept parameter
// (α, a score threshold, ...) and the result at it.
struct PrCurvePoint {
  double parameter = 0;
  PrecisionRecall result;
};

// The highest recall among points with precision 1 and at least one
// detection; 0 if there is none.
double recall_at_full_precision(const std::vector<PrCurvePoint>& curve);

// The curve obtained by keeping only detections with score ≥ t, for t at
// every distinct score (increasing t): what can be read from a detections
// file alone, without re-running detection. One sort, then one pass:
// O(detections × log) time. InvalidArgument as evaluate_detections, or for a
// NaN score.
std::vector<PrCurvePoint> pr_curve_by_score(const std::vector<Detection>& detections,
                                            const GroundTruth& truth);

}  // namespace binbow::loop