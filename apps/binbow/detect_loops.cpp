// binbow detect-loops: run the paper's loop detector over an image sequence.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "binbow/error.h"
#include "binbow/loop/report.h"
#include "binbow/loop/run_record.h"
#include "binbow/loop/sequence.h"
#include "binbow/loop/similarity.h"
#include "binbow/vision/features.h"
#include "binbow/vocabulary.h"
#include "commands.h"
#include "core/output_path.h"
#include "default_vocabulary.h"
#include "extractor_options.h"
#include "image_source_options.h"
#include "interruption.h"
#include "invocation.h"
#include "loop_params_options.h"
#include "output_options.h"
#include "progress.h"
#include "saved_state_descriptor.h"
#include "threads_options.h"

namespace binbow::cli {
namespace {

struct DetectLoopsArguments {
  std::string vocab;
  bool online_vocabulary = false;
  std::string save_vocabulary;
  OnlineVocabularyOptions online_options;
  std::string scoring;
  std::string save_state;
  std::string resume_state;
  // Whether the options a saved state can answer were given.
  bool descriptor_given = false;
  bool vocab_given = false;
  std::string descriptor;  // "": the vocabulary's (kDefaultDescriptor online)
  int max_features = 0;
  std::string params;
  std::string params_overrides;  // the parameter flags, a JSON object
  bool print_params = false;
  std::string report;
  bool timing = false;
  bool json = false;
  std::string output;
  std::vector<std::string> inputs;
  vision::ImageSourceOptions source;
  unsigned threads = 0;
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

void print_status_counts(bool summary_on_stderr, const loop::StatusCounts& counts) {
  print_summary(summary_on_stderr, "frames by status:\n");
  for (std::size_t value = 0; value < counts.size(); ++value)
    print_summary(summary_on_stderr, "  %s: %zu\n",
                  loop::to_string(static_cast<loop::LoopStatus>(value)), counts[value]);
}

// What the command line said and the run wrote, for the summary and --json.
struct DetectLoopsOutcome {
  std::string run_record;  // empty: none (-o -, /dev/null, a FIFO)
  std::string saved_state, saved_vocabulary, report;
};

// --json: the summary as one object on stdout (docs/cli.md).
void print_json_summary(const DetectLoopsArguments& arguments, loop::SequenceDetector& sequence,
                        const loop::LoopRunFiles& outputs, const DetectLoopsOutcome& outcome) {
  using Json = nlohmann::ordered_json;
  const auto path_or_null = [](const std::string& path) {
    return path.empty() ? Json(nullptr) : Json(path);
  };
  Json statuses = Json::object();
  const loop::StatusCounts& counts = sequence.status_counts();
  for (std::size_t value = 0; value < counts.size(); ++value)
    statuses[loop::to_string(static_cast<loop::LoopStatus>(value))] = counts[value];
  Json summary = {{"binbow_version", BINBOW_VERSION},
                  {"loops_csv", arguments.output},
                  {"run_record", path_or_null(outcome.run_record)},
                  {"frames", outputs.frames()},
                  {"loops", outputs.detections().size()},
                  {"unreadable_frames", sequence.unreadable_frames()},
                  {"skipped_frames", sequence.skipped_frames()},
                  {"frequency_hz", sequence.params().frequency},
                  {"frequency_origin", sequence.frequency_origin()},
                  {"frames_by_status", statuses},
                  {"saved_state", path_or_null(outcome.saved_state)},
                  {"saved_vocabulary", path_or_null(outcome.saved_vocabulary)},
                  {"report", path_or_null(outcome.report)}};
  if (arguments.timing) {
    Json stages = Json::array();
    for (const loop::StageTiming& stage : outputs.timing())
      stages.push_back({{"stage", stage.stage},
                        {"mean_ms", stage.mean()},
                        {"median_ms", stage.median()},
                        {"max_ms", stage.max()}});
    summary["timing"] = stages;
  }
  // Invalid UTF-8 in a file name is replaced rather than refused.
  std::printf("%s\n", summary.dump(2, ' ', false, Json::error_handler_t::replace).c_str());
}

// With --resume-state, what the command line leaves open comes from the
// saved state (its kind, its descriptor); what it says must agree with it.
void adopt_saved_state(DetectLoopsArguments& arguments, const loop::LoopDetectorFileInfo& saved) {
  const std::string& path = arguments.resume_state;
  if (saved.online && arguments.vocab_given)
    throw CLI::ValidationError("--resume-state " + path +
                               " holds an online vocabulary's state; --vocab conflicts with it "
                               "(use --online-vocabulary or nothing)");
  if (!saved.online && arguments.online_vocabulary)
    throw CLI::ValidationError("--resume-state " + path +
                               " holds a fixed vocabulary's state; --online-vocabulary conflicts "
                               "with it (give the vocabulary it was run with, --vocab)");
  arguments.online_vocabulary = saved.online;
  check_saved_descriptor(path, saved);
  if (!saved.descriptor.empty()) {
    if (arguments.descriptor_given && arguments.descriptor != saved.descriptor)
      throw CLI::ValidationError("--resume-state " + path + " was run with " + saved.descriptor +
                                 " descriptors; --descriptor " + arguments.descriptor +
                                 " conflicts with it");
    arguments.descriptor = saved.descriptor;
  }
}

// --print-params: the paper's defaults, then --params, then the parameter
// flags, as a parameter file that --params reads back to the same values.
void print_params(const DetectLoopsArguments& arguments) {
  loop::LoopDetectorParams params;
  if (!arguments.params.empty()) params = loop::LoopDetectorParams::load(arguments.params);
  if (!arguments.params_overrides.empty())
    params = loop::LoopDetectorParams::from_json(arguments.params_overrides, "the parameter flags",
                                                 params);
  std::cout << params.to_json() << '\n' << std::flush;
}

void run_detect_loops(DetectLoopsArguments arguments) {
  if (arguments.print_params) {
    print_params(arguments);
    return;
  }
  if (arguments.output.empty()) throw CLI::RequiredError("-o,--output");
  if (arguments.inputs.empty()) throw CLI::RequiredError("inputs");
  // Where the loops go: "-" is stdout, which then carries nothing else.
  const bool loops_on_stdout = is_standard_output(arguments.output);
  if (loops_on_stdout && arguments.json)
    throw CLI::ValidationError(
        "--json and -o - both write to standard output; give -o a file name");
  const std::string loops_csv = output_file(arguments.output);
  // Everything that can be checked is checked before the sequence is read.
  loop::LoopDetectorFileInfo saved;
  if (!arguments.resume_state.empty()) {
    saved = loop::LoopDetector::inspect(arguments.resume_state);
    adopt_saved_state(arguments, saved);
  }
  if (!arguments.scoring.empty())
    arguments.online_options.scoring = parse_scoring(arguments.scoring);
  if (!arguments.online_vocabulary) check_vocabulary_given(arguments.vocab, arguments.descriptor);
  CreatedFolders folders;
  folders.prepare_file("-o", arguments.output);
  refuse_standard_output("--save-vocabulary", arguments.save_vocabulary);
  refuse_standard_output("--save-state", arguments.save_state);
  if (!arguments.save_vocabulary.empty())
    folders.prepare_file("--save-vocabulary", arguments.save_vocabulary);
  if (!arguments.save_state.empty()) folders.prepare_file("--save-state", arguments.save_state);
  if (!arguments.report.empty()) folders.prepare_directory("--report", arguments.report);
  // The extractor is the vocabulary's unless --descriptor says otherwise.
  Vocabulary vocabulary;
  std::string vocabulary_path;
  if (!arguments.online_vocabulary)
    vocabulary_path = load_loop_vocabulary(arguments.vocab, arguments.descriptor, vocabulary);
  else if (arguments.descriptor.empty())
    arguments.descriptor = kDefaultDescriptor;
  loop::SequenceOptions options;
  options.descriptor = arguments.descriptor;
  options.max_features = arguments.max_features;
  options.source = arguments.source;
  options.params_file = arguments.params;
  options.params_overrides = arguments.params_overrides;
  options.threads = arguments.threads;
  options.extractor = vision::make_extractor(arguments.descriptor, arguments.max_features);
  loop::LoopRun run;
  run.online_vocabulary = arguments.online_vocabulary;
  run.online_options = arguments.online_options;
  std::unique_ptr<loop::SequenceDetector> detector;
  if (arguments.online_vocabulary) {
    if (!arguments.resume_state.empty())
      detector = std::make_unique<loop::SequenceDetector>(
          arguments.inputs, loop::LoopDetector::load(arguments.resume_state), options);
    else
      detector = std::make_unique<loop::SequenceDetector>(arguments.inputs,
                                                          arguments.online_options, options);
  } else {
    run.vocabulary = vocabulary_path;
    if (!arguments.resume_state.empty())
      detector = std::make_unique<loop::SequenceDetector>(
          arguments.inputs, loop::LoopDetector::load(arguments.resume_state, std::move(vocabulary)),
          options);
    else
      detector = std::make_unique<loop::SequenceDetector>(arguments.inputs, std::move(vocabulary),
                                                          options);
  }
  if (!arguments.resume_state.empty()) {
    note("resuming after %zu frames from %s\n", saved.frames, arguments.resume_state.c_str());
    run.resumed_from = absolute(arguments.resume_state);
    run.resumed_frames = saved.frames;
    if (saved.online) {
      const OnlineVocabulary* words = detector->detector().online_vocabulary();
      run.online_options = words->options();
    }
  }
  loop::SequenceDetector& sequence = *detector;
  run.descriptor = arguments.descriptor;
  run.max_features = arguments.max_features;
  run.params_json = sequence.params().to_json();
  run.provenance = {BINBOW_VERSION, invocation().started_utc, invocation().command_line};
  run.source = arguments.source;
  for (const std::string& input : arguments.inputs) run.inputs.push_back(absolute(input));

  throw_if_interrupted();  // loading the vocabulary, listing the inputs may take long
  const long long known = sequence.size();
  Progress progress("detecting loops", known > 0 ? static_cast<std::size_t>(known) : 0);
  loop::LoopRunFiles outputs(loops_csv, run);
  DetectLoopsOutcome outcome;
  if (!detail::is_written_in_place(loops_csv))
    outcome.run_record = loop::LoopRun::path_for(arguments.output);
  loop::SequenceFrame frame;
  while (sequence.next(frame)) {
    warn_if_unreadable(frame.file, frame.unreadable);
    outputs.add(frame);
    progress.update(outputs.frames());  // a check point
  }
  progress.finish();
  if (outputs.frames() == 0) throw InvalidArgument("detect-loops: no images found in the inputs");
  // From here on the outputs and the state are written whole.
  throw_if_interrupted();
  outputs.commit();
  if (!arguments.save_state.empty()) {
    sequence.detector().save(arguments.save_state);
    outcome.saved_state = arguments.save_state;
    note("state: %zu frames -> %s\n", sequence.detector().size(), arguments.save_state.c_str());
  }
  if (!arguments.save_vocabulary.empty()) {
    BuildOptions build;
    build.descriptor = arguments.descriptor;
    sequence.detector().online_vocabulary()->to_vocabulary(build).save(arguments.save_vocabulary);
    outcome.saved_vocabulary = arguments.save_vocabulary;
    note("online vocabulary: %zu words -> %s\n",
         sequence.detector().online_vocabulary()->word_count(), arguments.save_vocabulary.c_str());
  }

  // The summary: results on stdout, unless stdout carries the loops or
  // --json's object (then on stderr, where a log keeps it).
  const loop::LoopDetectorParams& params = sequence.params();
  const bool summary_on_stderr = loops_on_stdout || arguments.json;
  print_summary(summary_on_stderr, "%zu frames, %zu loops -> %s\n", outputs.frames(),
                outputs.detections().size(), arguments.output.c_str());
  if (sequence.unreadable_frames() > 0)
    print_summary(summary_on_stderr, "frames unreadable: %zu\n", sequence.unreadable_frames());
  if (arguments.source.skip_unreadable)
    print_summary(summary_on_stderr, "skipped frames: %zu\n", sequence.skipped_frames());
  print_summary(summary_on_stderr, "frequency: %s (%s)\n", hertz(params.frequency).c_str(),
                sequence.frequency_origin().c_str());
  print_status_counts(summary_on_stderr, sequence.status_counts());
  const std::string no_candidates = loop::no_candidate_reason(params, outputs.frames());
  if (!no_candidates.empty())
    std::fprintf(stderr,
                 "binbow: warning: %s; set a smaller \"dislocal\" with --params (a JSON file "
                 "such as {\"dislocal\": 5}) or --dislocal 5\n",
                 no_candidates.c_str());
  if (arguments.timing && !arguments.json)
    std::fprintf(loops_on_stdout ? stderr : stdout, "%s",
                 loop::format_timing_table(outputs.timing()).c_str());
  if (!arguments.report.empty()) {
    throw_if_interrupted();  // the report's similarity matrix may take long
    loop::LoopReport report;
    report.title = "binbow loop detection";
    report.provenance = run.provenance;
    report.facts = {{"inputs", run.inputs.front() + (run.inputs.size() > 1 ? " ..." : "")},
                    {"frames", std::to_string(outputs.frames())},
                    {"loops", std::to_string(outputs.detections().size())},
                    {"frequency", hertz(params.frequency)},
                    {"vocabulary", run.online_vocabulary ? "online" : run.vocabulary},
                    {"descriptor", run.descriptor}};
    report.params_json = run.params_json;
    report.timing = outputs.timing();
    // From the features the detector kept for the geometric check.
    if (params.geometric_check != loop::GeometricCheck::kNone)
      report.similarity = loop::similarity_matrix(sequence.detector());
    const auto& detections = outputs.detections();
    for (std::size_t i = 0; i < detections.size(); ++i)
      report.loops.push_back({detections[i],
                              i < outputs.loops().size() ? outputs.loops()[i].inliers
                                                         : std::vector<std::array<float, 4>>{},
                              -1});
    outcome.report = loop::write_loop_report(arguments.report, report);
    note("report: %s\n", outcome.report.c_str());
  }
  if (arguments.json) print_json_summary(arguments, sequence, outputs, outcome);
  std::fflush(stdout);
}

}  // namespace

void add_detect_loops_command(CLI::App& app) {
  auto arguments = std::make_shared<DetectLoopsArguments>();
  CLI::App* command = app.add_subcommand(
      "detect-loops",
      "Detect loop closures in an image sequence (Galvez-Lopez & Tardos 2012, Section V)");
  CLI::Option* vocab =
      command->add_option("--vocab", arguments->vocab,
                          "Vocabulary file (any supported format); default: the bundled "
                          "data/vocab/<descriptor>_default.bbw (orb and brief only)");
  CLI::Option* online =
      command->add_flag("--online-vocabulary", arguments->online_vocabulary,
                        "No pre-trained vocabulary: grow binary words from the sequence itself "
                        "(docs/online-vocabulary.md)");
  online->excludes(vocab);
  command
      ->add_option("--save-vocabulary", arguments->save_vocabulary,
                   std::string("With --online-vocabulary: after the run, export the grown words "
                               "as a fixed vocabulary (.bbw) for later runs") +
                       kOutputFolderParentsHelp)
      ->needs(online);
  // OnlineVocabularyOptions, one flag per field (docs/online-vocabulary.md).
  const OnlineVocabularyOptions defaults;
  std::vector<CLI::Option*> online_options = {
      command
          ->add_option("--new-word-distance", arguments->online_options.new_word_distance,
                       "With --online-vocabulary: a descriptor farther than this fraction of its "
                       "bits from every word becomes a new word")
          ->check(CLI::Range(0.0, 1.0))
          ->capture_default_str(),
      command
          ->add_option("--purge-after-images", arguments->online_options.purge_after_images,
                       "With --online-vocabulary: purge a word seen in a single image after "
                       "this many further images (0: never)")
          ->capture_default_str(),
      command
          ->add_option("--trees", arguments->online_options.trees,
                       "With --online-vocabulary: search trees [1, 16]")
          ->capture_default_str(),
      command
          ->add_option("--branching", arguments->online_options.branching,
                       "With --online-vocabulary: branching of the search trees [2, 64]")
          ->capture_default_str(),
      command
          ->add_option("--leaf-size", arguments->online_options.leaf_size,
                       "With --online-vocabulary: words of a search-tree leaf before it splits "
                       "[1, 4096]")
          ->capture_default_str(),
      command
          ->add_option("--max-checks", arguments->online_options.max_checks,
                       "With --online-vocabulary: words compared per search at most (more: "
                       "closer to exact, slower)")
          ->capture_default_str(),
      command->add_flag("--exact", arguments->online_options.exact,
                        "With --online-vocabulary: exact nearest-word search (slower)"),
      command
          ->add_option("--scoring", arguments->scoring,
                       "With --online-vocabulary: l1, l2, chi-square, kl, bhattacharyya or "
                       "dot-product")
          ->default_str(to_string(defaults.scoring)),
      command
          ->add_option("--seed", arguments->online_options.seed,
                       "With --online-vocabulary: seed of the search trees' random centres")
          ->capture_default_str()};
  for (CLI::Option* option : online_options) option->needs(online);
  add_vocabulary_extractor_options(command, arguments->descriptor, arguments->max_features);
  CLI::Option* params =
      command->add_option("--params", arguments->params,
                          "Loop detector parameters, JSON or YAML (keys as LoopDetectorParams); "
                          "keys it omits keep their defaults, whose frame counts (dislocal, ...) "
                          "follow the frames processed per second of a video");
  command->add_option("--save-state", arguments->save_state,
                      std::string("After the run, save the detector's whole state (.bbld) for "
                                  "--resume-state") +
                          kOutputFolderParentsHelp);
  CLI::Option* resume =
      command->add_option("--resume-state", arguments->resume_state,
                          "Start from a state saved by --save-state: its frames, parameters and "
                          "vocabulary kind (an online one's words too); new frames continue its "
                          "numbering. A fixed vocabulary must be the one it was run with");
  resume->excludes(params);
  auto param_flags = std::make_shared<LoopParamFlags>();
  add_loop_param_flags(command, *param_flags);
  for (const auto& [key, option] : param_flags->options) resume->excludes(option);
  command->add_flag("--print-params", arguments->print_params,
                    "Print the loop detector parameters as a --params file (JSON): the paper's "
                    "defaults, then --params, then the parameter flags; reads no images (a "
                    "video's frame rate is not applied: pass --frequency)");
  for (CLI::Option* option : online_options) resume->excludes(option);
  command->add_option("--report", arguments->report,
                      std::string("Write an HTML report into this directory") + kOutputFolderHelp);
  command->add_flag("--timing", arguments->timing,
                    "Print mean, median and max milliseconds per frame of each stage (with "
                    "--json: its \"timing\" key)");
  command->add_flag("--json", arguments->json,
                    "Print the summary as one JSON object on stdout (other lines go to stderr)");
  command->add_option("-o,--output", arguments->output,
                      std::string("Detected loops, CSV: query_index,match_index,query_file,"
                                  "match_file,score,inliers (a run record <output>.run.json is "
                                  "written beside it, none for -); required unless "
                                  "--print-params") +
                          kOutputFileHelp + " (the summary then goes to stderr)");
  command->add_option("inputs", arguments->inputs,
                      "Image files, directories, videos or text lists of images (required "
                      "unless --print-params)");
  add_image_source_options(command, arguments->source);
  add_skip_unreadable_option(command, arguments->source);
  add_threads_option(command, arguments->threads);
  command->callback([arguments, command, param_flags] {
    DetectLoopsArguments given = *arguments;
    given.params_overrides = loop_param_overrides(*param_flags);
    given.descriptor_given = !given.descriptor.empty();
    given.vocab_given = command->count("--vocab") > 0;
    run_detect_loops(std::move(given));
  });
}

}  // namespace binbow::cli
