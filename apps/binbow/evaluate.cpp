// binbow evaluate: precision and recall of detected loops against ground truth.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/evaluation.h"
#include "binbow/loop/explanation.h"
#include "binbow/loop/misses.h"
#include "binbow/loop/report.h"
#include "binbow/loop/run_record.h"
#include "binbow/loop/similarity.h"
#include "binbow/loop/sweep.h"
#include "binbow/vision/features.h"
#include "binbow/vocabulary.h"
#include "commands.h"
#include "default_vocabulary.h"
#include "output_options.h"
#include "progress.h"

namespace binbow::cli {
namespace {

struct EvaluateArguments {
  std::string ground_truth;
  int ground_truth_base = -1;
  bool sweep = false;
  std::string sweep_parameter = "alpha";
  std::vector<double> sweep_values;  // empty: loop::default_sweep_values
  std::string report;
  std::string detections;
};

// One progress line per stage the library reports.
class StageProgress {
 public:
  void operator()(const std::string& stage, std::size_t done, std::size_t total) {
    if (stage != stage_) {
      finish();
      progress_ = std::make_unique<Progress>(stage, total);
      stage_ = stage;
    }
    progress_->update(done);
  }
  void finish() {
    if (progress_) progress_->finish();
  }

 private:
  std::unique_ptr<Progress> progress_;
  std::string stage_;
};

// The recorded run's vocabulary and features, read once for the sweep and
// the similarity matrix.
struct RunInputs {
  Vocabulary vocabulary;
  loop::RunFeatures features;
};

RunInputs read_run_inputs(const loop::LoopRun& run) {
  RunInputs inputs;
  // The run record names the extractor the run used: one binbow cannot make is
  // an error naming the record, before the vocabulary is checked against it.
  loop::make_run_extractor(run);
  std::string descriptor = run.descriptor;
  if (!run.online_vocabulary) load_loop_vocabulary(run.vocabulary, descriptor, inputs.vocabulary);
  StageProgress progress;
  inputs.features =
      loop::extract_run_features(run, [&](const std::string& stage, std::size_t done,
                                          std::size_t total) { progress(stage, done, total); });
  progress.finish();
  return inputs;
}

void run_evaluate(const EvaluateArguments& arguments) {
  if (!arguments.report.empty()) prepare_output_directory("--report", arguments.report);
  // An unknown parameter is a usage error before anything is read.
  const std::vector<double> sweep_values =
      arguments.sweep ? loop::sweep_values(arguments.sweep_parameter, arguments.sweep_values)
                      : std::vector<double>{};

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

  // Features are extracted once, for the sweep and the report's similarity matrix.
  std::unique_ptr<RunInputs> inputs;
  if (run && arguments.sweep) {
    inputs = std::make_unique<RunInputs>(read_run_inputs(*run));
  } else if (run && !arguments.report.empty()) {
    try {
      inputs = std::make_unique<RunInputs>(read_run_inputs(*run));
    } catch (const Error& e) {  // the report is still worth writing
      std::fprintf(stderr, "note: no similarity matrix in the report: %s\n", e.what());
    }
  }

  std::vector<loop::PrCurvePoint> curve;
  std::string swept;
  if (arguments.sweep) {
    if (run) {
      StageProgress progress;
      curve = loop::sweep_parameter(*run, inputs->features, inputs->vocabulary, truth,
                                    arguments.sweep_parameter, sweep_values,
                                    [&](const std::string& stage, std::size_t done,
                                        std::size_t total) { progress(stage, done, total); });
      progress.finish();
      swept = arguments.sweep_parameter;
    } else {
      std::fprintf(stderr,
                   "note: no run record %s; the curve thresholds the scores of %s instead of "
                   "re-running detection\n",
                   run_path.c_str(), arguments.detections.c_str());
      curve = loop::pr_curve_by_score(detections, truth);
      swept = "score";
    }
    std::printf("recall at 100%% precision: %.6g\n", loop::recall_at_full_precision(curve));
    if (const loop::PrCurvePoint* best = loop::full_precision_point(curve))
      std::printf("reached at %s: %.6g\n", swept.c_str(), best->parameter);
    const int width = std::max<int>(8, static_cast<int>(swept.size()));
    std::printf("%-*s %10s %10s %10s\n", width, swept.c_str(), "precision", "recall", "detections");
    for (const auto& p : curve)
      std::printf("%-*.3g %10.4f %10.4f %10zu\n", width, p.parameter, p.result.precision,
                  p.result.recall, p.result.detections);
  }
  std::fflush(stdout);

  if (!arguments.report.empty()) {
    loop::LoopReport report;
    report.title = "binbow loop detection: evaluation";
    report.facts = {{"detections", arguments.detections}, {"ground truth", arguments.ground_truth}};
    report.has_result = true;
    report.result = result;
    report.curve = curve;
    report.curve_parameter = swept;
    report.recall_at_full_precision = loop::recall_at_full_precision(curve);
    report.missed = missed;
    report.truth = truth;
    if (run) {
      report.facts.emplace_back("vocabulary", run->online_vocabulary ? "online" : run->vocabulary);
      report.facts.emplace_back("descriptor", run->descriptor);
      report.facts.emplace_back("frames", std::to_string(run->frames.size()));
      report.params_json = run->params_json;
      report.timing = run->timing;
    }
    if (inputs) {
      StageProgress progress;
      progress("similarity matrix", 0, 1);
      report.similarity =
          run->online_vocabulary
              ? loop::online_similarity_matrix(
                    vision::make_extractor(run->descriptor, run->max_features)->code_size(),
                    inputs->features.features, run->online_options)
              : loop::similarity_matrix(inputs->vocabulary, inputs->features.features);
      progress("similarity matrix", 1, 1);
      progress.finish();
    }
    if (inputs) {
      // Detection re-run with its decisions recorded: why each false loop and miss.
      StageProgress progress;
      try {
        const loop::RunExplanations explained = loop::explain_run(
            *run, inputs->features, inputs->vocabulary, truth, loop::kExplainedPictures,
            [&](const std::string& stage, std::size_t done, std::size_t total) {
              progress(stage, done, total);
            });
        report.has_explanations = true;
        report.explanations = explained.cases;
        report.explanations_note = explained.note;
        if (!explained.note.empty()) std::fprintf(stderr, "warning: %s\n", explained.note.c_str());
      } catch (const Error& e) {  // the report is still worth writing
        std::fprintf(stderr, "note: no explanations in the report: %s\n", e.what());
      }
      progress.finish();
    }
    // The run's loops by (query, match): one lookup per detection, not a scan.
    std::map<std::pair<std::size_t, std::size_t>, const loop::LoopRecord*> recorded;
    if (run)
      for (const loop::LoopRecord& r : run->loops) recorded[{r.query, r.match}] = &r;
    for (const loop::Detection& d : detections) {
      loop::ReportLoop entry{d, {}, truth.is_loop(d.query, d.match) ? 1 : 0};
      const auto found = recorded.find({d.query, d.match});
      if (found != recorded.end()) entry.inliers = found->second->inliers;
      report.loops.push_back(std::move(entry));
    }
    const std::string page = loop::write_loop_report(arguments.report, report);
    std::fprintf(stderr, "report: %s\n", page.c_str());
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
