// binbow detect-loops: run the paper's loop detector over an image sequence.
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/evaluation.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/vocabulary.h"
#include "commands.h"
#include "core/file_io.h"
#include "default_vocabulary.h"
#include "extractor_options.h"
#include "image_source_options.h"
#include "loop_report.h"
#include "loop_run.h"
#include "output_options.h"
#include "progress.h"

namespace binbow::cli {
namespace {

struct DetectLoopsArguments {
  std::string vocab;
  std::string descriptor = kDefaultDescriptor;
  int max_features = 0;
  std::string params;
  std::string report;
  bool timing = false;
  std::string output;
  std::vector<std::string> inputs;
  vision::ImageSourceOptions source;
};

std::string absolute(const std::string& path) {
  std::error_code error;
  const auto p = std::filesystem::absolute(path, error);
  return error ? path : p.lexically_normal().string();
}

std::string hertz(double frequency) {
  char text[32];
  std::snprintf(text, sizeof text, "%g Hz", frequency);
  return text;
}

// Why the detector runs at params.frequency, for the summary.
std::string frequency_origin(const loop::LoopDetectorParams& params,
                             const loop::LoopDetectorParams& defaults, double frame_rate) {
  if (params.frequency != defaults.frequency) return "--params";
  if (frame_rate > 0) return "video frames processed per second";
  return "the paper's default; images have no frame rate";
}

// Loop candidates of frame t are frames j < t - dislocal, so a sequence not
// longer than dislocal + 1 frames cannot close a loop whatever it shows.
void warn_if_no_frame_can_have_a_candidate(const loop::LoopDetectorParams& params,
                                           std::size_t frames) {
  if (static_cast<std::size_t>(params.dislocal) + 1 < frames) return;
  std::fprintf(stderr,
               "binbow: warning: no frame can have a loop candidate: candidates must be more "
               "than dislocal = %d frames older than the query, and the sequence has only %zu "
               "frames; set a smaller \"dislocal\" with --params (a JSON file such as "
               "{\"dislocal\": 5})\n",
               params.dislocal, frames);
}

// Frames per LoopStatus, indexed by its value (consecutive from kLoopDetected).
using StatusCounts =
    std::array<std::size_t,
               static_cast<std::size_t>(loop::LoopStatus::kNoGeometricConsistency) + 1>;

void print_status_counts(const StatusCounts& counts) {
  std::fprintf(stderr, "frames by status:\n");
  for (std::size_t value = 0; value < counts.size(); ++value)
    std::fprintf(stderr, "  %s: %zu\n", loop::to_string(static_cast<loop::LoopStatus>(value)),
                 counts[value]);
}

void run_detect_loops(const DetectLoopsArguments& arguments) {
  // Everything that can be checked is checked before the sequence is read.
  check_vocabulary_given(arguments.vocab, arguments.descriptor);
  prepare_output_file("-o", arguments.output);
  if (!arguments.report.empty()) prepare_output_directory("--report", arguments.report);
  vision::ImageSource source(arguments.inputs, arguments.source);
  const double frame_rate = source.frame_rate();
  const loop::LoopDetectorParams defaults =
      frame_rate > 0 ? loop::LoopDetectorParams::for_frequency(frame_rate)
                     : loop::LoopDetectorParams{};
  const loop::LoopDetectorParams params =
      arguments.params.empty() ? defaults
                               : loop::LoopDetectorParams::load(arguments.params, defaults);
  const auto extractor = vision::make_extractor(arguments.descriptor, arguments.max_features);
  Vocabulary vocabulary;
  LoopRun run;
  run.vocabulary = load_loop_vocabulary(arguments.vocab, arguments.descriptor,
                                        extractor->code_size(), vocabulary);
  run.descriptor = arguments.descriptor;
  run.max_features = arguments.max_features;
  run.params_json = params.to_json();
  run.source = arguments.source;
  for (const std::string& input : arguments.inputs) run.inputs.push_back(absolute(input));

  loop::LoopDetector detector(std::move(vocabulary), params);
  const long long known = source.size();
  Progress progress("detecting loops", known > 0 ? static_cast<std::size_t>(known) : 0);
  // loops.csv and its run record appear together or not at all.
  detail::StagedFiles outputs;
  std::FILE* const csv = outputs.stage(arguments.output);
  const std::string record_path = LoopRun::path_for(arguments.output);
  LoopRunWriter record(outputs.stage(record_path), record_path, run);
  std::vector<std::string> names;  // of every frame: a loop's match_file
  std::vector<loop::Detection> detections;
  StatusCounts status_counts{};
  std::vector<double> scales;  // Frame::scale of every frame, to record inliers in file pixels
  std::vector<std::array<float, 4>> inliers;
  vision::Frame frame;
  while (source.next(frame)) {
    const auto start = std::chrono::steady_clock::now();
    const vision::Features features = extractor->extract(frame.image);
    const double features_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const loop::LoopResult result = detector.process(features);
    const loop::LoopStageTimes& t = result.times;
    record.add_frame(
        {frame.name, loop::to_string(result.status),
         result.has_candidate ? static_cast<long long>(result.match) : -1, result.score,
         result.normalised_score, result.inliers.size()},
        {features_ms, t.transform_ms, t.query_ms, t.islands_ms, t.verification_ms, t.insertion_ms});
    names.push_back(frame.name);
    scales.push_back(frame.scale);
    ++status_counts[static_cast<std::size_t>(result.status)];
    if (result.detection()) {
      detections.push_back({result.query, result.match, frame.name, names[result.match],
                            result.normalised_score, result.inliers.size()});
      if (record.keeps_next_loop()) {
        const Span<vision::Keypoint> match_points = detector.keypoints(result.match);
        inliers.clear();
        const auto qs = static_cast<float>(frame.scale);
        const auto ms = static_cast<float>(scales[result.match]);
        for (const vision::Correspondence& c : result.inliers) {
          const vision::Keypoint& q = features.keypoints[c.first];
          const vision::Keypoint& m = match_points[c.second];
          inliers.push_back({q.x / qs, q.y / qs, m.x / ms, m.y / ms});
        }
        record.add_loop(result.query, result.match, inliers);
      }
    }
    progress.update(names.size());
  }
  progress.finish();
  if (names.empty()) throw InvalidArgument("detect-loops: no images found in the inputs");

  const std::string csv_text = loop::format_detections_csv(detections);
  detail::write_all(csv, csv_text.data(), csv_text.size(), arguments.output);
  record.finish();
  outputs.commit();
  std::fprintf(stderr, "%zu frames, %zu loops -> %s\n", names.size(), detections.size(),
               arguments.output.c_str());
  if (source.unreadable_frames() > 0)
    std::fprintf(stderr, "frames unreadable: %zu\n", source.unreadable_frames());
  std::fprintf(stderr, "frequency: %s (%s)\n", hertz(params.frequency).c_str(),
               frequency_origin(params, defaults, frame_rate).c_str());
  print_status_counts(status_counts);
  warn_if_no_frame_can_have_a_candidate(params, names.size());
  if (arguments.timing) std::cout << format_timing_table(record.timing()) << std::flush;
  if (!arguments.report.empty()) {
    LoopReport report;
    report.title = "binbow loop detection";
    report.facts = {{"inputs", run.inputs.front() + (run.inputs.size() > 1 ? " ..." : "")},
                    {"frames", std::to_string(names.size())},
                    {"loops", std::to_string(detections.size())},
                    {"frequency", hertz(params.frequency)},
                    {"vocabulary", run.vocabulary},
                    {"descriptor", run.descriptor}};
    report.params_json = run.params_json;
    report.timing = record.timing();
    for (std::size_t i = 0; i < detections.size(); ++i)
      report.loops.push_back({detections[i],
                              i < record.loops().size() ? record.loops()[i].inliers
                                                        : std::vector<std::array<float, 4>>{},
                              -1});
    const std::string page = write_loop_report(arguments.report, report);
    std::fprintf(stderr, "report: %s\n", page.c_str());
  }
}

}  // namespace

void add_detect_loops_command(CLI::App& app) {
  auto arguments = std::make_shared<DetectLoopsArguments>();
  CLI::App* command = app.add_subcommand(
      "detect-loops",
      "Detect loop closures in an image sequence (Galvez-Lopez & Tardos 2012, Section V)");
  command->add_option("--vocab", arguments->vocab,
                      "Vocabulary file (any supported format); default: the bundled "
                      "data/vocab/<descriptor>_default.bbw (orb and brief only)");
  add_extractor_options(command, arguments->descriptor, arguments->max_features);
  command->add_option("--params", arguments->params,
                      "Loop detector parameters, JSON or YAML (keys as LoopDetectorParams); "
                      "keys it omits keep their defaults, whose frame counts (dislocal, ...) "
                      "follow the frames processed per second of a video");
  command->add_option("--report", arguments->report, "Write an HTML report into this directory");
  command->add_flag("--timing", arguments->timing,
                    "Print mean, median and max milliseconds per frame of each stage");
  command
      ->add_option("-o,--output", arguments->output,
                   "Detected loops, CSV: query_index,match_index,query_file,match_file,score,"
                   "inliers (a run record <output>.run.json is written beside it)")
      ->required();
  command
      ->add_option("inputs", arguments->inputs,
                   "Image files, directories, videos or text lists of images")
      ->required();
  add_image_source_options(command, arguments->source);
  command->callback([arguments] { run_detect_loops(*arguments); });
}

}  // namespace binbow::cli
