// binbow detect-loops: run the paper's loop detector over an image sequence.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/vision/evaluation.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "binbow/vision/loop_detector.h"
#include "binbow/vocabulary.h"
#include "commands.h"
#include "default_vocabulary.h"
#include "extractor_options.h"
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
};

std::string absolute(const std::string& path) {
  std::error_code error;
  const auto p = std::filesystem::absolute(path, error);
  return error ? path : p.lexically_normal().string();
}

void run_detect_loops(const DetectLoopsArguments& arguments) {
  // Everything that can be checked is checked before the sequence is read.
  check_vocabulary_given(arguments.vocab, arguments.descriptor);
  prepare_output_file("-o", arguments.output);
  if (!arguments.report.empty()) prepare_output_directory("--report", arguments.report);
  const vision::LoopDetectorParams params =
      arguments.params.empty() ? vision::LoopDetectorParams{}
                               : vision::LoopDetectorParams::load(arguments.params);
  const auto extractor = vision::make_extractor(arguments.descriptor, arguments.max_features);
  Vocabulary vocabulary;
  LoopRun run;
  run.vocabulary = load_loop_vocabulary(arguments.vocab, arguments.descriptor,
                                        extractor->code_size(), vocabulary);
  run.descriptor = arguments.descriptor;
  run.max_features = arguments.max_features;
  run.params_json = params.to_json();
  for (const std::string& input : arguments.inputs) run.inputs.push_back(absolute(input));

  vision::LoopDetector detector(std::move(vocabulary), params);
  vision::ImageSource source(arguments.inputs);
  const long long known = source.size();
  Progress progress("detecting loops", known > 0 ? static_cast<std::size_t>(known) : 0);
  run.timing = {{"features", {}}, {"transform", {}},    {"query", {}},
                {"islands", {}},  {"verification", {}}, {"insertion", {}}};
  std::vector<vision::Detection> detections;
  vision::Frame frame;
  while (source.next(frame)) {
    const auto start = std::chrono::steady_clock::now();
    const vision::Features features = extractor->extract(frame.image);
    run.timing[0].ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
    const vision::LoopResult result = detector.process(features);
    run.timing[1].ms.push_back(result.times.transform_ms);
    run.timing[2].ms.push_back(result.times.query_ms);
    run.timing[3].ms.push_back(result.times.islands_ms);
    run.timing[4].ms.push_back(result.times.verification_ms);
    run.timing[5].ms.push_back(result.times.insertion_ms);
    run.frames.push_back({frame.name, vision::to_string(result.status),
                          result.has_candidate ? static_cast<long long>(result.match) : -1,
                          result.score, result.normalised_score, result.inliers.size()});
    if (result.detection()) {
      detections.push_back({result.query, result.match, frame.name, run.frames[result.match].file,
                            result.normalised_score, result.inliers.size()});
      LoopRecord loop{result.query, result.match, {}};
      const Span<vision::Keypoint> match_points = detector.keypoints(result.match);
      for (const vision::Correspondence& c : result.inliers) {
        const vision::Keypoint& q = features.keypoints[c.first];
        const vision::Keypoint& m = match_points[c.second];
        loop.inliers.push_back({q.x, q.y, m.x, m.y});
      }
      run.loops.push_back(std::move(loop));
    }
    progress.update(run.frames.size());
  }
  progress.finish();
  if (run.frames.empty()) throw InvalidArgument("detect-loops: no images found in the inputs");

  vision::write_detections_csv(arguments.output, detections);
  run.save(LoopRun::path_for(arguments.output));
  std::fprintf(stderr, "%zu frames, %zu loops -> %s\n", run.frames.size(), detections.size(),
               arguments.output.c_str());
  if (source.unreadable_frames() > 0)
    std::fprintf(stderr, "frames unreadable: %zu\n", source.unreadable_frames());
  if (arguments.timing) std::cout << format_timing_table(run.timing) << std::flush;
  if (!arguments.report.empty()) {
    LoopReport report;
    report.title = "binbow loop detection";
    report.facts = {{"inputs", run.inputs.front() + (run.inputs.size() > 1 ? " ..." : "")},
                    {"frames", std::to_string(run.frames.size())},
                    {"loops", std::to_string(detections.size())},
                    {"vocabulary", run.vocabulary},
                    {"descriptor", run.descriptor}};
    report.params_json = run.params_json;
    report.timing = run.timing;
    for (std::size_t i = 0; i < detections.size(); ++i)
      report.loops.push_back({detections[i], run.loops[i].inliers, -1});
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
                      "Loop detector parameters, JSON or YAML (keys as LoopDetectorParams)");
  command->add_option("--report", arguments->report, "Write an HTML report into this directory");
  command->add_flag("--timing", arguments->timing,
                    "Print mean, median and max milliseconds per frame of each stage");
  command
      ->add_option("-o,--output", arguments->output,
                   "Detected loops, CSV: query_index,match_index,query_file,match_file,score,"
                   "inliers (a run record <output>.run.json is written beside it)")
      ->required();
  command->add_option("inputs", arguments->inputs, "Image directory, video or text list of images")
      ->required();
  command->callback([arguments] { run_detect_loops(*arguments); });
}

}  // namespace binbow::cli
