// `binbow evaluate --sweep` and `--report`: detection re-run from the run
// record for the precision-recall curve, and the HTML report (evaluate.h).
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/explanation.h"
#include "binbow/loop/report.h"
#include "binbow/loop/similarity.h"
#include "binbow/loop/sweep.h"
#include "binbow/vision/features.h"
#include "binbow/vocabulary.h"
#include "default_vocabulary.h"
#include "evaluate.h"
#include "interruption.h"
#include "invocation.h"
#include "progress.h"

namespace binbow::cli {
namespace {

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

}  // namespace

std::vector<double> evaluate_sweep_values(const EvaluateArguments& arguments) {
  return loop::sweep_values(arguments.sweep_parameter, arguments.sweep_values);
}

SweepOutcome sweep_and_report(const EvaluateArguments& arguments, const Evaluation& evaluation) {
  const loop::LoopRun* run = evaluation.run;
  const loop::GroundTruth& truth = *evaluation.truth;
  const std::vector<loop::Detection>& detections = *evaluation.detections;
  const std::string& run_path = evaluation.run_path;
  const loop::PrecisionRecall& result = evaluation.result;
  const std::vector<loop::MissedLoop>& missed = evaluation.missed;
  const std::vector<double> sweep_values =
      arguments.sweep ? evaluate_sweep_values(arguments) : std::vector<double>{};

  // Features are extracted once, for the sweep and the report's similarity matrix.
  std::unique_ptr<RunInputs> inputs;
  if (run && arguments.sweep) {
    inputs = std::make_unique<RunInputs>(read_run_inputs(*run));
  } else if (run && !arguments.report.empty()) {
    try {
      inputs = std::make_unique<RunInputs>(read_run_inputs(*run));
    } catch (const Error& e) {  // the report is still worth writing
      note("note: no similarity matrix in the report: %s\n", e.what());
    }
  }

  SweepOutcome outcome;
  std::vector<loop::PrCurvePoint>& curve = outcome.curve;
  std::string& swept = outcome.swept;
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
      note(
          "note: no run record %s; the curve thresholds the scores of %s instead of "
          "re-running detection\n",
          run_path.c_str(), arguments.detections.c_str());
      curve = loop::pr_curve_by_score(detections, truth);
      swept = "score";
    }
    if (const loop::PrCurvePoint* best = loop::full_precision_point(curve))
      outcome.reached_at = best->parameter;
  }
  if (arguments.sweep && !arguments.json) {
    std::printf("recall at 100%% precision: %.6g\n", loop::recall_at_full_precision(curve));
    if (outcome.reached_at)
      std::printf("reached at %s: %.6g\n", swept.c_str(), *outcome.reached_at);
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
    report.provenance = {BINBOW_VERSION, invocation().started_utc, invocation().command_line};
    if (run) report.run_provenance = run->provenance;
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
        note("note: no explanations in the report: %s\n", e.what());
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
    throw_if_interrupted();
    outcome.report = loop::write_loop_report(arguments.report, report);
    note("report: %s\n", outcome.report.c_str());
  }
  return outcome;
}

}  // namespace binbow::cli
