#include "binbow/loop/sweep.h"

#include <cmath>

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

// `base` with one field set, through the parameter file's validation.
LoopDetectorParams with_value(const LoopDetectorParams& base, const std::string& parameter,
                              double value) {
  nlohmann::json fields = nlohmann::json::parse(base.to_json());
  if (!fields.contains(parameter) || !fields.at(parameter).is_number())
    throw InvalidArgument("cannot sweep \"" + parameter +
                          "\": not a numeric loop detector parameter");
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

}  // namespace

std::vector<PrCurvePoint> sweep_parameter(const LoopRun& run, const Vocabulary& vocabulary,
                                          const GroundTruth& truth, const std::string& parameter,
                                          const std::vector<double>& values,
                                          const SweepProgress& progress) {
  const LoopDetectorParams base = LoopDetectorParams::from_json(run.params_json);
  std::vector<LoopDetectorParams> settings;
  for (double value : values) settings.push_back(with_value(base, parameter, value));

  const auto extractor = vision::make_extractor(run.descriptor, run.max_features);
  vision::ImageSource source(run.inputs, run.source);
  std::vector<vision::Features> features;
  std::vector<std::string> names;
  vision::Frame frame;
  while (source.next(frame)) {
    features.push_back(extractor->extract(frame.image));
    names.push_back(frame.name);
    if (progress) progress("extracting features", features.size(), run.frames.size());
  }
  if (features.size() != run.frames.size())
    throw InvalidArgument("the inputs of the recorded run now have " +
                          std::to_string(features.size()) + " frames instead of " +
                          std::to_string(run.frames.size()) + "; run detect-loops again");

  std::vector<PrCurvePoint> curve;
  for (std::size_t v = 0; v < values.size(); ++v) {
    LoopDetector detector(vocabulary, settings[v]);
    std::vector<Detection> detections;
    for (std::size_t i = 0; i < features.size(); ++i) {
      const LoopResult r = detector.process(features[i]);
      if (r.detection())
        detections.push_back(
            {r.query, r.match, names[i], names[r.match], r.normalised_score, r.inliers.size()});
    }
    curve.push_back({values[v], evaluate_detections(detections, truth)});
    if (progress) progress("sweeping " + parameter, curve.size(), values.size());
  }
  return curve;
}

}  // namespace binbow::loop
