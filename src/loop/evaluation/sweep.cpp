#include "binbow/loop/sweep.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <nlohmann/json.hpp>

#include "binbow/error.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"

namespace binbow::loop {

std::vector<double> default_alpha_values() {
  std::vector<double> values;
  for (int i = 0; i <= 20; ++i) values.push_back(i * 0.05);
  for (double v : {1.2, 1.5, 2.0, 3.0}) values.push_back(v);
  return values;
}

namespace {

[[noreturn]] void throw_not_sweepable(const std::string& parameter) {
  std::string choices;
  for (const std::string& name : sweepable_parameters())
    choices += (choices.empty() ? "" : ", ") + name;
  throw InvalidArgument("cannot sweep \"" + parameter +
                        "\": not a numeric loop detector parameter (choices: " + choices + ")");
}

// `base` with one field set, through the parameter file's validation.
LoopDetectorParams with_value(const LoopDetectorParams& base, const std::string& parameter,
                              double value) {
  nlohmann::json fields = nlohmann::json::parse(base.to_json());
  if (!fields.contains(parameter) || !fields.at(parameter).is_number() || parameter == "frequency")
    throw_not_sweepable(parameter);
  if (fields.at(parameter).is_number_integer()) {
    if (!(std::abs(value) <= 1e15) || value != std::trunc(value))
      throw InvalidArgument("cannot sweep \"" + parameter + "\" over " + std::to_string(value) +
                            ": it takes whole numbers");
    fields[parameter] = static_cast<long long>(value);
  } else {
    fields[parameter] = value;
  }
  // Every field is in the text, so a "frequency" key rescales nothing else.
  try {
    return LoopDetectorParams::from_json(fields.dump(), "the sweep of " + parameter, base);
  } catch (const FileError& e) {  // a value, not a file, is wrong
    throw InvalidArgument(e.what());
  }
}

// A failure caused by what `run` says names its record.
[[noreturn]] void fail_run(const LoopRun& run, const std::string& problem) {
  if (run.path.empty()) throw InvalidArgument(problem);
  throw FileError(run.path, problem);
}

// `make` (something built from what `run` says), its InvalidArgument naming the record.
template <typename Make>
auto from_run(const LoopRun& run, Make make) {
  try {
    return make();
  } catch (const InvalidArgument& e) {
    fail_run(run, e.what());
  }
}

LoopDetectorParams run_params(const LoopRun& run) {
  return LoopDetectorParams::from_json(run.params_json,
                                       run.path.empty() ? "the run's parameters" : run.path);
}

}  // namespace

std::unique_ptr<vision::FeatureExtractor> make_run_extractor(const LoopRun& run) {
  return from_run(run, [&] { return vision::make_extractor(run.descriptor, run.max_features); });
}

std::vector<std::string> sweepable_parameters() {
  std::vector<std::string> names;
  const auto fields = nlohmann::ordered_json::parse(LoopDetectorParams{}.to_json());
  for (const auto& [key, value] : fields.items())
    if (value.is_number() && key != "frequency") names.push_back(key);
  return names;
}

std::vector<double> default_sweep_values(const std::string& parameter) {
  const std::vector<std::string> names = sweepable_parameters();
  if (std::find(names.begin(), names.end(), parameter) == names.end())
    throw_not_sweepable(parameter);
  if (parameter == "alpha") return default_alpha_values();
  // Around the paper's defaults (in brackets), within each parameter's range.
  static const std::map<std::string, std::vector<double>> ranges = {
      {"min_normalisation_score", {0, 0.001, 0.0025, 0.005, 0.01, 0.02, 0.05, 0.1}},  // 0.005
      {"dislocal", {0, 5, 10, 15, 20, 30, 40, 60, 100}},                              // 20
      {"max_db_results", {1, 5, 10, 20, 50, 100, 200}},                               // 50
      {"max_intra_island_gap", {1, 2, 3, 4, 5, 8, 12}},                               // 3
      {"min_matches_per_island", {1, 2, 3, 4, 5, 8}},                                 // 1
      {"k", {0, 1, 2, 3, 4, 5, 6, 8, 10}},                                            // 3
      {"max_distance_between_islands", {0, 1, 2, 3, 4, 5, 8, 12}},                    // 3
      {"max_distance_between_queries", {1, 2, 3, 4, 5, 8}},                           // 2
      {"direct_index_levels", {0, 1, 2, 3, 4, 5, 6}},                                 // 2
      {"max_verified_entries", {1, 2, 3, 4, 5, 10}},                                  // 1
      {"max_localisation_checks", {1, 2, 4, 8, 16, 32, 50}},                          // 8
      {"max_neighbor_ratio", {0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 1}},   // 0.6
      {"max_match_distance", {0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5, 0.75, 1}},        // 1
      {"min_inliers", {8, 10, 12, 14, 16, 20, 25, 30, 40, 50}},                       // 12
      {"max_reprojection_error", {0.5, 1, 1.5, 2, 2.5, 3, 4, 5, 8}},                  // 2
      {"ransac_confidence", {0.9, 0.95, 0.99, 0.995, 0.999}},                         // 0.99
      {"max_ransac_iterations", {50, 100, 200, 500, 1000, 2000, 5000}},               // 500
      {"min_inlier_ratio", {0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6}},                        // 0
      {"min_inlier_spread", {0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4}},                     // 0
      {"min_uncorroborated_inliers", {0, 13, 14, 16, 18, 20, 25, 30}},                // 16
      {"min_uncorroborated_view_agreement", {0, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7}},       // 0.5
      {"corroboration_distance", {1, 2, 3, 4, 5, 6, 8, 12}},                          // 4
      {"corroboration_horizon", {1, 4, 6, 8, 10, 12, 16, 20}},                        // 10
      {"corroboration_pace_tolerance", {0, 0.1, 0.2, 0.25, 0.3, 0.5, 0.75, 1}},       // 0.25
  };
  const auto found = ranges.find(parameter);
  if (found == ranges.end())
    throw InvalidArgument("no default values to sweep \"" + parameter + "\"; give them");
  return found->second;
}

std::vector<double> sweep_values(const std::string& parameter, const std::vector<double>& given) {
  const std::vector<double> values = given.empty() ? default_sweep_values(parameter) : given;
  for (const double value : values) with_value(LoopDetectorParams{}, parameter, value);
  return values;
}

const PrCurvePoint* full_precision_point(const std::vector<PrCurvePoint>& curve) {
  const PrCurvePoint* best = nullptr;
  for (const PrCurvePoint& p : curve)
    if (p.result.false_positives == 0 && p.result.detections > 0 &&
        (best == nullptr || p.result.recall >= best->result.recall))
      best = &p;
  return best;
}

std::vector<PrCurvePoint> curve_in_recall_order(std::vector<PrCurvePoint> curve) {
  std::stable_sort(curve.begin(), curve.end(), [](const PrCurvePoint& a, const PrCurvePoint& b) {
    return a.result.recall < b.result.recall ||
           (a.result.recall == b.result.recall && a.result.precision > b.result.precision);
  });
  return curve;
}

RunFeatures extract_run_features(const LoopRun& run, const SweepProgress& progress) {
  const auto extractor = make_run_extractor(run);
  vision::ImageSourceOptions options = vision::limit_for_extractor(run.source, *extractor);
  // A run that skipped unreadable frames is re-run the same way: each keeps
  // its entry, without features.
  options.skip_unreadable =
      std::any_of(run.frames.begin(), run.frames.end(),
                  [](const FrameRecord& f) { return f.status == kUnreadableFrameStatus; });
  vision::ImageSource source =
      from_run(run, [&] { return vision::ImageSource(run.inputs, options); });
  RunFeatures out;
  vision::Frame frame;
  while (source.next(frame)) {
    if (frame.unreadable.empty()) {
      out.features.push_back(vision::extract_features(*extractor, frame.image, frame.name));
    } else {
      out.features.emplace_back().descriptors = DescriptorMatrix(extractor->code_size());
    }
    out.names.push_back(frame.name);
    out.scales.push_back(frame.scale);
    if (progress) progress("extracting features", out.features.size(), run.frames.size());
  }
  if (out.features.size() != run.frames.size())
    fail_run(run, "the inputs of the recorded run now have " + std::to_string(out.features.size()) +
                      " frames instead of " + std::to_string(run.frames.size()) +
                      "; run detect-loops again");
  return out;
}

std::vector<PrCurvePoint> sweep_parameter(const LoopRun& run, const RunFeatures& features,
                                          const Vocabulary& vocabulary, const GroundTruth& truth,
                                          const std::string& parameter,
                                          const std::vector<double>& values,
                                          const SweepProgress& progress) {
  const LoopDetectorParams base = run_params(run);
  std::vector<LoopDetectorParams> settings;
  for (double value : values) settings.push_back(with_value(base, parameter, value));

  // A run with an online vocabulary grows its words again at every value.
  OnlineVocabularyOptions online_options = run.online_options;
  online_options.descriptor = run.descriptor;
  const std::size_t code_size = run.online_vocabulary ? make_run_extractor(run)->code_size() : 0;
  std::vector<PrCurvePoint> curve;
  for (std::size_t v = 0; v < values.size(); ++v) {
    LoopDetector detector =
        run.online_vocabulary
            ? from_run(run,
                       [&] { return LoopDetector::online(code_size, online_options, settings[v]); })
            : LoopDetector(vocabulary, settings[v]);
    std::vector<Detection> detections;
    for (std::size_t i = 0; i < features.features.size(); ++i) {
      const LoopResult r = detector.process(features.features[i]);
      if (r.detection())
        detections.push_back({r.query, r.match, features.names[i], features.names[r.match],
                              r.normalised_score, r.inliers.size()});
    }
    curve.push_back({values[v], evaluate_detections(detections, truth)});
    if (progress) progress("sweeping " + parameter, curve.size(), values.size());
  }
  return curve;
}

std::vector<PrCurvePoint> sweep_parameter(const LoopRun& run, const Vocabulary& vocabulary,
                                          const GroundTruth& truth, const std::string& parameter,
                                          const std::vector<double>& values,
                                          const SweepProgress& progress) {
  // Parameter errors before the (long) feature extraction.
  const LoopDetectorParams base = run_params(run);
  for (double value : values) with_value(base, parameter, value);
  return sweep_parameter(run, extract_run_features(run, progress), vocabulary, truth, parameter,
                         values, progress);
}

}  // namespace binbow::loop
