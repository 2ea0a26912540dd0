// Precision–recall curves by re-running detection: the run recorded beside a
// loops.csv (LoopRun) is run again over its inputs for each value of one
// parameter, features extracted once (and shared with the similarity matrix,
// similarity.h). What `binbow evaluate --sweep [--sweep-param NAME]` draws.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/run_record.h"
#include "binbow/vision/features.h"
#include "binbow/vocabulary.h"

namespace binbow::loop {

// The α values swept by default: the paper's range 0–1 in steps of 0.05,
// then beyond 1 (η exceeds 1 when the loop image is more similar than the
// previous frame).
std::vector<double> default_alpha_values();

// The LoopDetectorParams fields a sweep can set: every numeric field but
// frequency (informative only), in to_json() order.
std::vector<std::string> sweepable_parameters();
// The values swept when none are given: α as default_alpha_values(), and a
// range around the default for k, min_inliers, max_reprojection_error,
// max_neighbor_ratio, dislocal and the other numeric fields, increasing.
// Throws InvalidArgument naming the choices for a name that is not in
// sweepable_parameters().
std::vector<double> default_sweep_values(const std::string& parameter);
// `given`, or default_sweep_values() when it is empty, checked: throws
// InvalidArgument naming the choices for an unknown parameter, or naming a
// value out of the parameter's range (before any work is done).
std::vector<double> sweep_values(const std::string& parameter,
                                 const std::vector<double>& given = {});

// The point where recall_at_full_precision() is reached: the highest recall
// with precision 1 and a detection; of several, the last in curve order (the
// highest value of an increasing sweep: the strictest α still reaching it).
// nullptr if there is none.
const PrCurvePoint* full_precision_point(const std::vector<PrCurvePoint>& curve);

// The curve as it is drawn: by increasing recall, then decreasing precision;
// points equal in both keep their sweep order.
std::vector<PrCurvePoint> curve_in_recall_order(std::vector<PrCurvePoint> curve);

// Told the stage ("extracting features", "sweeping <parameter>"), the steps
// done and the steps in that stage.
using SweepProgress =
    std::function<void(const std::string& stage, std::size_t done, std::size_t total)>;

// For each value, the run's parameters with `parameter` (a LoopDetectorParams
// field name, as in a --params file) set to it, detection re-run over the
// run's inputs and evaluated against `truth`. `vocabulary` must be the run's
// (unused, and may be empty, for a run with an online vocabulary: the words
// grow again from the frames, with the default online vocabulary options).
// Throws InvalidArgument for an unknown parameter or a value out of its
// range; errors of the run itself as extract_run_features.
std::vector<PrCurvePoint> sweep_parameter(const LoopRun& run, const Vocabulary& vocabulary,
                                          const GroundTruth& truth, const std::string& parameter,
                                          const std::vector<double>& values,
                                          const SweepProgress& progress = {});

// The features of a recorded run's frames, extracted once (as the run did)
// for any number of sweeps and the similarity matrix.
struct RunFeatures {
  std::vector<vision::Features> features;  // frame i
  std::vector<std::string> names;          // vision::Frame::name of frame i
  std::vector<double> scales;              // vision::Frame::scale of frame i (file pixels × it)
};
// The run's feature extractor (its descriptor and max_features).
std::unique_ptr<vision::FeatureExtractor> make_run_extractor(const LoopRun& run);

// Errors caused by what the run says (its descriptor, parameters, source
// options, online vocabulary options, a number of frames the inputs no
// longer have) are FileErrors naming its record, LoopRun::path (an
// InvalidArgument for a run not loaded from a file); an unreadable input is
// a FileError naming the input.
RunFeatures extract_run_features(const LoopRun& run, const SweepProgress& progress = {});
std::vector<PrCurvePoint> sweep_parameter(const LoopRun& run, const RunFeatures& features,
                                          const Vocabulary& vocabulary, const GroundTruth& truth,
                                          const std::string& parameter,
                                          const std::vector<double>& values,
                                          const SweepProgress& progress = {});

}  // namespace binbow::loop
