// binbow evaluate: precision and recall of detected loops against ground
// truth; --sweep and --report are evaluate_report.cpp's (evaluate.h).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "binbow/error.h"
#include "binbow/loop/evaluation.h"
#include "binbow/loop/false_loops.h"
#include "binbow/loop/misses.h"
#include "binbow/loop/run_record.h"
#include "commands.h"
#include "evaluate.h"
#include "interruption.h"
#include "invocation.h"
#include "output_options.h"
#include "vision_commands.h"

namespace binbow::cli {
namespace {

void print_result(const loop::PrecisionRecall& result, const std::vector<loop::MissedLoop>& missed,
                  const std::vector<loop::FalseLoop>& wrong) {
  std::printf("precision: %.6g\nrecall: %.6g\n", result.precision, result.recall);
  std::printf(
      "detections: %zu\ntrue positives: %zu\nfalse positives: %zu\n"
      "queries with a loop: %zu\nqueries found: %zu\n",
      result.detections, result.true_positives, result.false_positives, result.queries_with_loops,
      result.queries_found);
  std::printf("missed loops: %zu\n", missed.size());
  for (const loop::MissedLoop& miss : missed)
    std::printf("%s\n", loop::format_missed_loop(miss).c_str());
  std::printf("false loops: %zu\n", wrong.size());
  for (const loop::FalseLoop& loop : wrong)
    std::printf("%s\n", loop::format_false_loop(loop).c_str());
  std::fflush(stdout);
}

using Json = nlohmann::ordered_json;

Json json_of(const loop::PrecisionRecall& result) {
  return {{"precision", result.precision},
          {"recall", result.recall},
          {"detections", result.detections},
          {"true_positives", result.true_positives},
          {"false_positives", result.false_positives},
          {"queries_with_loops", result.queries_with_loops},
          {"queries_found", result.queries_found}};
}

// -1 (not known) as null.
Json known(long long value) {
  return value < 0 ? Json(nullptr) : Json(value);
}

// --json: the lines above and the sweep as one object (docs/cli.md).
void print_json(const EvaluateArguments& arguments, const std::string& run_path,
                const loop::LoopRun* run, const loop::PrecisionRecall& result,
                const std::vector<loop::MissedLoop>& missed,
                const std::vector<loop::FalseLoop>& wrong, const SweepOutcome& outcome) {
  Json summary = {{"binbow_version", BINBOW_VERSION},
                  {"loops_csv", arguments.detections},
                  {"ground_truth", arguments.ground_truth},
                  {"run_record", run ? Json(run_path) : Json(nullptr)}};
  summary.update(json_of(result));
  Json misses = Json::array();
  for (const loop::MissedLoop& miss : missed)
    misses.push_back({{"query", miss.query},
                      {"file", miss.file.empty() ? Json(nullptr) : Json(miss.file)},
                      {"status", miss.status.empty() ? Json(nullptr) : Json(miss.status)},
                      {"match", known(miss.match)},
                      {"candidate_right",
                       miss.candidate_right < 0 ? Json(nullptr) : Json(miss.candidate_right == 1)},
                      {"correspondences", known(miss.correspondences)},
                      {"inliers", known(miss.inliers)},
                      {"features", known(miss.features)}});
  summary["missed_loops"] = misses;
  Json false_loops = Json::array();
  for (const loop::FalseLoop& loop : wrong)
    false_loops.push_back(
        {{"query", loop.query},
         {"match", loop.match},
         {"file", loop.file.empty() ? Json(nullptr) : Json(loop.file)},
         {"inliers", loop.inliers},
         {"score", loop.score},
         {"accepted_by", loop.accepted_by.empty() ? Json(nullptr) : Json(loop.accepted_by)},
         {"localised_from", known(loop.localised_from)}});
  summary["false_loops"] = false_loops;
  if (arguments.sweep) {
    Json curve = Json::array();
    for (const loop::PrCurvePoint& point : outcome.curve) {
      Json entry = {{"value", point.parameter}};
      entry.update(json_of(point.result));
      curve.push_back(entry);
    }
    summary["sweep"] = {
        {"parameter", outcome.swept},
        {"recall_at_full_precision", loop::recall_at_full_precision(outcome.curve)},
        {"reached_at", outcome.reached_at ? Json(*outcome.reached_at) : Json(nullptr)},
        {"curve", curve}};
  }
  summary["report"] = outcome.report.empty() ? Json(nullptr) : Json(outcome.report);
  std::printf("%s\n", summary.dump(2, ' ', false, Json::error_handler_t::replace).c_str());
  std::fflush(stdout);
}

void run_evaluate(const EvaluateArguments& arguments) {
  CreatedFolders folders;
  if (!arguments.report.empty()) folders.prepare_directory("--report", arguments.report);
  // An unknown parameter is a usage error before anything is read.
  if (arguments.sweep) vision_commands().evaluate_sweep_values(arguments);

  const std::string run_path = loop::LoopRun::path_for(arguments.detections);
  std::unique_ptr<loop::LoopRun> run;
  if (std::filesystem::exists(run_path)) {
    run = std::make_unique<loop::LoopRun>(loop::LoopRun::load(run_path));
    if (!loop::check_loops_csv_of_run(*run, run_path, arguments.detections))
      std::fprintf(stderr,
                   "warning: %s was written before run records named their loops file; "
                   "nothing checks that %s belongs to it\n",
                   run_path.c_str(), arguments.detections.c_str());
  }
  if (run && !run->resumed_from.empty()) {
    // Its frames start after the state's, which the record cannot re-run.
    note(
        "note: %s resumed from %s after %zu frames; evaluating %s alone, without its run "
        "record\n",
        arguments.detections.c_str(), run->resumed_from.c_str(), run->resumed_frames,
        arguments.detections.c_str());
    run.reset();
  }
  if (arguments.sweep && !run && arguments.sweep_parameter != "alpha")
    throw InvalidArgument("--sweep-param " + arguments.sweep_parameter +
                          " re-runs detection, which needs the run record " + run_path +
                          " written by detect-loops beside " + arguments.detections);

  loop::GroundTruthOptions options;
  options.pairs_index_base = arguments.ground_truth_base;
  // The run's frames size the ground truth: a larger matrix is read only that far.
  if (run) options.frames = run->frames.size();
  const loop::GroundTruth truth = loop::GroundTruth::load(arguments.ground_truth, options);
  const std::vector<loop::Detection> detections = loop::read_detections_csv(arguments.detections);
  loop::PrecisionRecall result;
  std::vector<loop::MissedLoop> missed;
  std::vector<loop::FalseLoop> wrong;
  const std::vector<loop::FrameRecord> no_record;
  const std::vector<loop::FrameRecord>& frames = run ? run->frames : no_record;
  try {
    result = loop::evaluate_detections(detections, truth);
    missed = loop::missed_loops(frames, detections, truth);
    wrong = loop::false_loops(frames, detections, truth);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(arguments.detections + ": " + e.what() + " (wrong --gt?)");
  }

  if (run && run->frames.size() != truth.frames())
    std::fprintf(stderr, "warning: %zu frames were processed but the ground truth has %zu\n",
                 run->frames.size(), truth.frames());

  if (!arguments.json) print_result(result, missed, wrong);

  SweepOutcome outcome;
  if (arguments.sweep || !arguments.report.empty()) {
    throw_if_interrupted();  // a large ground truth may have taken long
    Evaluation evaluation;
    evaluation.run = run.get();
    evaluation.run_path = run_path;
    evaluation.truth = &truth;
    evaluation.detections = &detections;
    evaluation.result = result;
    evaluation.missed = missed;
    outcome = vision_commands().sweep_and_report(arguments, evaluation);
  }
  if (arguments.json) print_json(arguments, run_path, run.get(), result, missed, wrong, outcome);
}

}  // namespace

void add_evaluate_command(CLI::App& app) {
  auto arguments = std::make_shared<EvaluateArguments>();
  CLI::App* command =
      app.add_subcommand("evaluate", "Precision and recall of detected loops against ground truth");
  command
      ->add_option("--gt", arguments->ground_truth,
                   "Ground truth: image matrix (.bmp/.png, row = query, non-zero = same place), "
                   "MATLAB .mat matrix, or text pairs \"query match\"")
      ->required();
  command
      ->add_option("--gt-base", arguments->ground_truth_base,
                   "Index base of text pairs, 0 or 1 (default: from a \"0-based\"/\"1-based\" "
                   "comment, or 0 if an index 0 appears)")
      ->check(CLI::IsMember({0, 1}));
  CLI::Option* sweep = command->add_flag(
      "--sweep", arguments->sweep,
      "Re-run detection over a parameter (from the run record beside the CSV) for the "
      "precision-recall curve and the recall at 100% precision; without a run record, "
      "threshold the scores");
  command
      ->add_option("--sweep-param", arguments->sweep_parameter,
                   "Loop detector parameter to sweep: alpha (default), k, min_inliers, "
                   "max_reprojection_error, max_neighbor_ratio, dislocal, ... (any numeric "
                   "parameter of a --params file)")
      ->needs(sweep);
  command
      ->add_option("--sweep-values", arguments->sweep_values,
                   "Values to sweep, comma-separated (default: a range around the default)")
      ->delimiter(',')
      ->needs(sweep);
  command->add_option("--report", arguments->report,
                      std::string("Write an HTML report into this directory") + kOutputFolderHelp);
  command->add_flag("--json", arguments->json,
                    "Print the results (and --sweep's curve) as one JSON object on stdout");
  command->add_option("loops", arguments->detections, "loops.csv written by detect-loops")
      ->required();
  command->callback([arguments] { run_evaluate(*arguments); });
}

}  // namespace binbow::cli
