// Precision–recall curves by re-running detection: the run recorded beside a
// loops.csv (LoopRun) is run again over its inputs for each value of one
// parameter, features extracted once. What `binbow evaluate --sweep` draws.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/run_record.h"
#include "binbow/vocabulary.h"

namespace binbow::loop {

// The α values swept by default: the paper's range 0–1 in steps of 0.05,
// then beyond 1 (η exceeds 1 when the loop image is more similar than the
// previous frame).
std::vector<double> default_alpha_values();

// Told the stage ("extracting features", "sweeping <parameter>"), the steps
// done and the steps in that stage.
using SweepProgress =
    std::function<void(const std::string& stage, std::size_t done, std::size_t total)>;

// For each value, the run's parameters with `parameter` (a LoopDetectorParams
// field name, as in a --params file) set to it, detection re-run over the
// run's inputs and evaluated against `truth`. `vocabulary` must be the run's.
// Throws InvalidArgument for an unknown parameter or a value out of its
// range, or when the inputs no longer have the recorded number of frames.
std::vector<PrCurvePoint> sweep_parameter(const LoopRun& run, const Vocabulary& vocabulary,
                                          const GroundTruth& truth, const std::string& parameter,
                                          const std::vector<double>& values,
                                          const SweepProgress& progress = {});

}  // namespace binbow::loop
