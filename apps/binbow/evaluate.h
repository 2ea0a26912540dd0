// `binbow evaluate`: the evaluation itself reads only text and the ground
// truth, and runs in the binbow executable without OpenCV (evaluate.cpp);
// --sweep and --report re-run detection on the recorded run's images and are
// in the binbow_cli_vision module (evaluate_report.cpp), loaded when asked for.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/misses.h"
#include "binbow/loop/run_record.h"

namespace binbow::cli {

struct EvaluateArguments {
  std::string ground_truth;
  int ground_truth_base = -1;
  bool sweep = false;
  std::string sweep_parameter = "alpha";
  std::vector<double> sweep_values;  // empty: loop::default_sweep_values
  std::string report;
  bool json = false;  // one JSON object on stdout instead of the lines
  std::string detections;
};

// What the evaluation read and found, for the sweep and the report.
struct Evaluation {
  const loop::LoopRun* run = nullptr;  // null without a run record that can be re-run
  std::string run_path;                // where the run record is (or would be)
  const loop::GroundTruth* truth = nullptr;
  const std::vector<loop::Detection>* detections = nullptr;
  loop::PrecisionRecall result;
  std::vector<loop::MissedLoop> missed;
};

// What --sweep and --report found and wrote, for --json.
struct SweepOutcome {
  std::vector<loop::PrCurvePoint> curve;  // empty without --sweep
  std::string swept;                      // the parameter swept, or "score"
  // loop::full_precision_point's parameter; none without a point at 100% precision.
  std::optional<double> reached_at;
  std::string report;  // the page written; empty without --report
};

// --sweep's values (loop::sweep_values), checked before anything is read.
std::vector<double> evaluate_sweep_values(const EvaluateArguments& arguments);
// Prints --sweep's curve (unless --json) and writes --report.
SweepOutcome sweep_and_report(const EvaluateArguments& arguments, const Evaluation& evaluation);

}  // namespace binbow::cli
