// binbow evaluate: precision and recall of detected loops against ground
// truth; --sweep and --report are evaluate_report.cpp's (evaluate.h).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/evaluation.h"
#include "binbow/loop/misses.h"
#include "binbow/loop/run_record.h"
#include "commands.h"
#include "evaluate.h"
#include "interruption.h"
#include "output_options.h"
#include "vision_commands.h"

namespace binbow::cli {
namespace {

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
    std::fprintf(stderr,
                 "note: %s resumed from %s after %zu frames; evaluating %s alone, without its "
                 "run record\n",
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
  try {
    result = loop::evaluate_detections(detections, truth);
    missed =
        loop::missed_loops(run ? run->frames : std::vector<loop::FrameRecord>{}, detections, truth);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(arguments.detections + ": " + e.what() + " (wrong --gt?)");
  }

  if (run && run->frames.size() != truth.frames())
    std::fprintf(stderr, "warning: %zu frames were processed but the ground truth has %zu\n",
                 run->frames.size(), truth.frames());

  std::printf("precision: %.6g\nrecall: %.6g\n", result.precision, result.recall);
  std::printf(
      "detections: %zu\ntrue positives: %zu\nfalse positives: %zu\n"
      "queries with a loop: %zu\nqueries found: %zu\n",
      result.detections, result.true_positives, result.false_positives, result.queries_with_loops,
      result.queries_found);
  std::printf("missed loops: %zu\n", missed.size());
  for (const loop::MissedLoop& miss : missed)
    std::printf("%s\n", loop::format_missed_loop(miss).c_str());
  std::fflush(stdout);

  if (arguments.sweep || !arguments.report.empty()) {
    throw_if_interrupted();  // a large ground truth may have taken long
    Evaluation evaluation;
    evaluation.run = run.get();
    evaluation.run_path = run_path;
    evaluation.truth = &truth;
    evaluation.detections = &detections;
    evaluation.result = result;
    evaluation.missed = std::move(missed);
    vision_commands().sweep_and_report(arguments, evaluation);
  }
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
  command->add_option("--report", arguments->report, "Write an HTML report into this directory");
  command->add_option("loops", arguments->detections, "loops.csv written by detect-loops")
      ->required();
  command->callback([arguments] { run_evaluate(*arguments); });
}

}  // namespace binbow::cli
