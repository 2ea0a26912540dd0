// `binbow bench`: end-to-end timings on real images — vocabulary load,
// features, transform, loop detection, and the database at a chosen size —
// as medians, so that users can compare machines and vocabularies.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "available_memory.h"
#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/loop/run_record.h"
#include "binbow/vision/features.h"
#include "binbow/vision/frame_pipeline.h"
#include "binbow/vision/image_source.h"
#include "commands.h"
#include "default_vocabulary.h"
#include "extractor_options.h"
#include "image_source_options.h"
#include "progress.h"
#include "threads_options.h"

namespace binbow::cli {

namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct BenchArguments {
  std::vector<std::string> inputs;
  std::string vocabulary;
  std::string descriptor;  // "": the vocabulary's
  int features = 0;
  std::size_t database_size = 10000;
  int load_repeats = 5;
  vision::ImageSourceOptions source;
  unsigned threads = 0;
};

struct Frame {
  vision::Features features;
};

// Entries in the database that estimates the memory of a larger one.
constexpr std::size_t kProbeEntries = 16384;

// The memory of a database of `entries` entries cycling through the frames'
// vectors, extrapolated from a database of kProbeEntries (or `entries` if
// fewer) filled so: what its second half added, per entry, for every further
// entry, plus the add timings (8 bytes an entry, up to twice that as their
// list grows), with a quarter more: filling 300,000 entries peaked at 1.2
// times the index's memory_usage(). Refused before the database is filled.
void refuse_database_beyond_memory(std::size_t entries, const Vocabulary& vocabulary,
                                   const std::vector<BowVector>& bows,
                                   const std::vector<FeatureVector>& direct) {
  const std::size_t probe_entries = std::min(entries, kProbeEntries);
  Database probe(vocabulary, DatabaseOptions{});
  double half = 0;
  for (std::size_t i = 0; i < probe_entries; ++i) {
    if (i == probe_entries / 2) half = static_cast<double>(probe.memory_usage());
    probe.add(bows[i % bows.size()], direct[i % direct.size()]);
  }
  const auto full = static_cast<double>(probe.memory_usage());
  const double per_entry = (full - half) / static_cast<double>(probe_entries - probe_entries / 2);
  constexpr double kPeakOverIndex = 1.25;
  const auto needed = static_cast<std::uint64_t>(
      kPeakOverIndex * (full + per_entry * static_cast<double>(entries - probe_entries)) +
      2 * sizeof(double) * static_cast<double>(entries));
  const std::uint64_t available = available_memory();
  if (available == 0 || needed <= available) return;
  throw InvalidArgument("--database-size " + std::to_string(entries) + " needs about " +
                        gibibytes(needed) + "; this machine has " + gibibytes(available) +
                        " available");
}

void run_bench(BenchArguments args) {
  check_vocabulary_given(args.vocabulary, args.descriptor);
  Vocabulary vocabulary;
  const std::string vocabulary_path =
      load_loop_vocabulary(args.vocabulary, args.descriptor, vocabulary);
  const std::shared_ptr<const vision::FeatureExtractor> extractor =
      vision::make_extractor(args.descriptor, args.features);

  // Each stage's samples in milliseconds: per load, per frame, per entry, per query.
  std::vector<loop::StageTiming> timing;
  auto stage = [&timing](const std::string& name) -> std::vector<double>& {
    timing.push_back({name, {}});
    return timing.back().ms;
  };

  auto& load = stage("vocabulary load");
  for (int i = 0; i < args.load_repeats; ++i) {
    const auto start = Clock::now();
    const Vocabulary v = load_vocabulary(vocabulary_path, VocabularyFormat::kAuto, args.descriptor);
    load.push_back(elapsed_ms(start));
  }

  std::vector<Frame> frames;
  auto& features = stage("features");
  {
    vision::FramePipeline pipeline(
        vision::ImageSource(args.inputs, vision::limit_for_extractor(args.source, *extractor)),
        extractor, {args.threads, 0});
    // Between frames delivered in order: what extraction costs a frame when
    // the pipeline's threads share the work.
    std::vector<double> delivered;
    const long long total = pipeline.size();
    Progress progress("features", total > 0 ? static_cast<std::size_t>(total) : 0);
    vision::ExtractedFrame frame;
    auto last = Clock::now();
    while (pipeline.next(frame)) {
      delivered.push_back(elapsed_ms(last));
      last = Clock::now();
      frames.push_back({std::move(frame.features)});
      features.push_back(frame.features_ms);
      progress.update(frames.size());
    }
    // After the loop: stage() may move the samples `features` refers to.
    stage("features, wall/frame, " + std::to_string(pipeline.threads()) + " threads") =
        std::move(delivered);
  }
  if (frames.empty()) throw InvalidArgument("bench: the input has no frames");

  const DatabaseOptions db_options;
  auto& transform = stage("transform: BoW + direct index");
  std::vector<BowVector> bows(frames.size());
  std::vector<FeatureVector> direct(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto start = Clock::now();
    vocabulary.transform(frames[i].features.descriptors, bows[i], direct[i],
                         db_options.direct_index_levels_up);
    transform.push_back(elapsed_ms(start));
  }

  refuse_database_beyond_memory(args.database_size, vocabulary, bows, direct);

  auto& detection = stage("loop detection, features excluded");
  {
    loop::LoopDetector detector(vocabulary);
    for (const Frame& frame : frames) {
      const auto start = Clock::now();
      detector.process(frame.features);
      detection.push_back(elapsed_ms(start));
    }
  }

  // The database filled to the requested size with the real frames' vectors
  // in turn: the posting lists then have the length real use gives them.
  Database database(vocabulary, db_options);
  auto& add = stage("database add, per entry");
  {
    Progress progress("database", args.database_size);
    for (std::size_t i = 0; i < args.database_size; ++i) {
      const auto start = Clock::now();
      database.add(bows[i % bows.size()], direct[i % direct.size()]);
      add.push_back(elapsed_ms(start));
      if (i % 256 == 0) progress.update(i);
    }
    progress.update(args.database_size);
  }
  auto& query = stage("database query, top 50, full size");
  for (const BowVector& bow : bows) {
    const auto start = Clock::now();
    const auto results = database.query(bow, 50);
    query.push_back(elapsed_ms(start));
  }

  std::printf("binbow bench: %zu frames, %s features, vocabulary %s\n", frames.size(),
              args.descriptor.c_str(), vocabulary.description().c_str());
  std::printf("database: %zu entries, %.1f MiB of index (%.1f KiB per entry)\n", database.size(),
              static_cast<double>(database.memory_usage()) / (1 << 20),
              static_cast<double>(database.memory_usage()) / 1024.0 /
                  static_cast<double>(std::max<std::size_t>(database.size(), 1)));
  std::printf("hamming kernel: %s\n\n", hamming_kernel_name());
  std::printf("%-36s %10s %10s %10s\n", "stage (ms)", "median", "mean", "max");
  for (const loop::StageTiming& t : timing)
    std::printf("%-36s %10.3f %10.3f %10.3f\n", t.stage.c_str(), t.median(), t.mean(), t.max());
}

}  // namespace

void add_bench_command(CLI::App& app) {
  auto args = std::make_shared<BenchArguments>();
  auto* cmd = app.add_subcommand(
      "bench", "Time every stage on real images: load, features, transform, detection, database");
  cmd->add_option("inputs", args->inputs, "Image directory, video or text list of images")
      ->required();
  cmd->add_option("--vocab", args->vocabulary,
                  "Vocabulary (any supported format); default: the bundled one for --descriptor "
                  "(orb and brief only)");
  add_vocabulary_extractor_options(cmd, args->descriptor, args->features);
  cmd->add_option("--database-size", args->database_size,
                  "Entries in the database for the add and query timings")
      ->check(CLI::Range(1, 10000000))
      ->capture_default_str();
  add_image_source_options(cmd, args->source);
  add_threads_option(cmd, args->threads);
  cmd->callback([args] { run_bench(*args); });
}

}  // namespace binbow::cli
