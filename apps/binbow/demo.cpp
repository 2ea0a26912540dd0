// `binbow demo`: loop detection and evaluation on the bundled real sequence
// with the bundled vocabulary — the whole system in one command, for a
// newcomer. It runs the very detect-loops and evaluate commands.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/run_record.h"
#include "commands.h"
#include "default_vocabulary.h"
#include "output_options.h"

namespace binbow::cli {

namespace {

namespace fs = std::filesystem;

// Runs one of binbow's commands in this process, exactly as on the command line.
void run_command(const std::vector<std::string>& arguments) {
  CLI::App app;
  add_detect_loops_command(app);
  add_evaluate_command(app);
  std::vector<std::string> reversed(arguments.rbegin(), arguments.rend());  // CLI11's order
  app.parse(reversed);
}

double median_ms_per_frame(const loop::LoopRun& run) {
  std::vector<double> total;
  for (const loop::StageTiming& stage : run.timing) {
    if (total.size() < stage.ms.size()) total.resize(stage.ms.size(), 0.0);
    for (std::size_t i = 0; i < stage.ms.size(); ++i) total[i] += stage.ms[i];
  }
  if (total.empty()) return 0;
  std::nth_element(total.begin(), total.begin() + static_cast<long>(total.size() / 2), total.end());
  return total[total.size() / 2];
}

void run_demo(const std::string& out_dir) {
  const std::string sample = find_bundled_data("samples/rtabmap", "the bundled sample sequence");
  const std::string frames = (fs::path(sample) / "samples").string();
  const std::string truth = (fs::path(sample) / "samples_GT.bmp").string();
  prepare_output_directory("--out", out_dir);
  const std::string loops = (fs::path(out_dir) / "loops.csv").string();

  std::printf("== binbow demo: loop closures in a real corridor sequence walked twice\n");
  std::printf("   frames: %s\n   ground truth: %s\n\n", frames.c_str(), truth.c_str());
  std::fflush(stdout);
  run_command({"detect-loops", "--descriptor", "orb", "-o", loops, frames});
  run_command({"evaluate", "--gt", truth, "--sweep", "--report", out_dir, loops});

  const loop::LoopRun run = loop::LoopRun::load(loop::LoopRun::path_for(loops));
  const loop::PrecisionRecall result =
      loop::evaluate_detections(loop::read_detections_csv(loops), loop::GroundTruth::load(truth));
  std::printf("\n== summary\n");
  std::printf("frames: %zu\n", run.frames.size());
  std::printf("loops found: %zu\n", result.detections);
  std::printf("precision: %.6g\n", result.precision);
  std::printf("recall: %.6g\n", result.recall);
  std::printf("time per frame: %.2f ms (median, features included)\n", median_ms_per_frame(run));
  std::printf("vocabulary: %s\n", run.vocabulary.c_str());
  std::printf("report: %s\n", (fs::absolute(out_dir) / "index.html").lexically_normal().c_str());
}

}  // namespace

void add_demo_command(CLI::App& app) {
  auto out_dir = std::make_shared<std::string>("binbow-demo");
  auto* cmd = app.add_subcommand(
      "demo", "Detect loops in the bundled sample sequence and evaluate them, with an HTML report");
  cmd->add_option("--out", *out_dir,
                  std::string("Directory for loops.csv and the report") + kOutputFolderHelp)
      ->capture_default_str();
  cmd->callback([out_dir] { run_demo(*out_dir); });
}

}  // namespace binbow::cli
