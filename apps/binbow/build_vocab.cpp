// binbow build-vocab: train a vocabulary tree from images.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "binbow/vocabulary.h"
#include "commands.h"
#include "core/parallel_for.h"
#include "extractor_options.h"
#include "image_source_options.h"
#include "invocation.h"
#include "output_options.h"
#include "progress.h"
#include "validators.h"

namespace binbow::cli {
namespace {

struct BuildVocabArguments {
  std::string descriptor = kDefaultDescriptor;
  std::uint32_t branching = 10;
  std::uint32_t levels = 6;
  std::string weighting = "tf-idf";
  std::string scoring = "l1";
  unsigned threads = 0;
  std::uint64_t seed = 0;
  std::size_t max_descriptors = 0;
  int features_per_image = 0;
  std::string output;
  std::vector<std::string> inputs;
  vision::ImageSourceOptions source;
};

// The descriptors of every image, one contiguous block; image i owns rows
// [offsets[i], offsets[i + 1]).
struct TrainingSet {
  DescriptorMatrix descriptors;
  std::vector<std::size_t> offsets{0};

  std::size_t images() const { return offsets.size() - 1; }
  std::vector<DescriptorView> views() const {
    std::vector<DescriptorView> result;
    result.reserve(images());
    for (std::size_t i = 0; i < images(); ++i) {
      result.push_back(descriptors.view().slice(offsets[i], offsets[i + 1] - offsets[i]));
    }
    return result;
  }
};

TrainingSet extract_training_set(const BuildVocabArguments& arguments) {
  // Frames are read in order and described in parallel batches, one extractor
  // per thread (OpenCV's detectors are not documented as thread-safe).
  const unsigned threads = detail::resolve_thread_count(arguments.threads);
  std::vector<std::unique_ptr<vision::FeatureExtractor>> extractors;
  for (unsigned t = 0; t < threads; ++t) {
    extractors.push_back(
        vision::make_extractor(arguments.descriptor, arguments.features_per_image));
  }
  vision::ImageSource source(arguments.inputs,
                             vision::limit_for_extractor(arguments.source, *extractors.front()));
  const long long known_size = source.size();
  Progress progress("reading images", known_size > 0 ? static_cast<std::size_t>(known_size) : 0);
  TrainingSet set;
  set.descriptors = DescriptorMatrix(extractors[0]->code_size());
  std::vector<vision::Frame> batch(4 * static_cast<std::size_t>(threads));
  std::vector<vision::Features> features(batch.size());
  for (bool more = true; more;) {
    std::size_t count = 0;
    while (count < batch.size() && (more = source.next(batch[count]))) ++count;
    detail::parallel_for(threads, count, [&](std::size_t i, unsigned worker) {
      features[i] = vision::extract_features(*extractors[worker], batch[i].image, batch[i].name);
    });
    for (std::size_t i = 0; i < count; ++i) {
      set.descriptors.append(features[i].descriptors.view());
      set.offsets.push_back(set.descriptors.rows());
    }
    progress.update(set.images());
  }
  progress.finish();
  if (set.images() == 0) throw InvalidArgument("build-vocab: no images found in the inputs");
  if (set.descriptors.empty()) {
    throw InvalidArgument("build-vocab: no features found in " + std::to_string(set.images()) +
                          " images");
  }
  return set;
}

// Keeps `limit` descriptors chosen uniformly at random (seeded), in their
// original order so every image keeps its own rows.
TrainingSet subsample(const TrainingSet& set, std::size_t limit, std::uint64_t seed) {
  const std::size_t total = set.descriptors.rows();
  if (limit == 0 || limit >= total) return set;
  std::vector<std::uint32_t> order(total);
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937_64 rng(seed ^ 0x5eedf00dcafe1234ull);
  // Partial Fisher–Yates with an explicit formula: std::shuffle and the
  // standard distributions are not portable across standard libraries.
  for (std::size_t i = 0; i < limit; ++i) {
    const std::size_t j = i + static_cast<std::size_t>(rng() % (total - i));
    std::swap(order[i], order[j]);
  }
  std::vector<bool> keep(total, false);
  for (std::size_t i = 0; i < limit; ++i) keep[order[i]] = true;

  TrainingSet result;
  result.descriptors = DescriptorMatrix(set.descriptors.code_size());
  result.descriptors.reserve(limit);
  for (std::size_t image = 0; image < set.images(); ++image) {
    for (std::size_t row = set.offsets[image]; row < set.offsets[image + 1]; ++row) {
      if (keep[row]) result.descriptors.append(set.descriptors.row(row));
    }
    result.offsets.push_back(result.descriptors.rows());
  }
  return result;
}

void run_build_vocab(const BuildVocabArguments& arguments) {
  BuildOptions options;
  options.descriptor = arguments.descriptor;
  options.branching = arguments.branching;
  options.levels = arguments.levels;
  options.weighting = parse_weighting(arguments.weighting);
  options.scoring = parse_scoring(arguments.scoring);
  options.threads = arguments.threads;
  options.seed = arguments.seed;
  // Checked before reading any image: a typo should not cost a long extraction.
  // Standard output has no extension to tell the format: binbow's own.
  const bool on_stdout = is_standard_output(arguments.output);
  if (!on_stdout) format_for_output(arguments.output);
  refuse_binary_on_terminal("-o", arguments.output, "a vocabulary");
  prepare_output_file("-o", arguments.output);

  const auto start = std::chrono::steady_clock::now();
  const TrainingSet set =
      subsample(extract_training_set(arguments), arguments.max_descriptors, arguments.seed);
  const double extraction_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  Progress progress("clustering", set.descriptors.rows());
  options.progress = [&progress](const BuildProgress& state) {
    progress.update(state.clustered_descriptors);
  };
  const auto build_start = std::chrono::steady_clock::now();
  const Vocabulary vocabulary = Vocabulary::build(set.views(), options);
  const double build_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
  progress.finish();

  if (on_stdout)
    vocabulary.save(output_file(arguments.output));
  else
    save_vocabulary(vocabulary, arguments.output);
  print_summary(on_stdout, "%s: %s\n", arguments.output.c_str(), vocabulary.description().c_str());
  print_summary(on_stdout, "trained on %zu descriptors from %zu images\n", set.descriptors.rows(),
                set.images());
  print_summary(on_stdout, "words: %zu, nodes: %zu\n", vocabulary.word_count(),
                vocabulary.node_count());
  print_summary(on_stdout, "time: %.2f s features, %.2f s clustering\n", extraction_seconds,
                build_seconds);
  if (summary_stream(on_stdout) != nullptr)  // a pass over every descriptor: only when shown
    print_summary(on_stdout, "mean quantisation error: %.2f bits\n",
                  vocabulary.mean_quantisation_error(set.descriptors.view()));
}

}  // namespace

void add_build_vocab_command(CLI::App& app) {
  auto arguments = std::make_shared<BuildVocabArguments>();
  CLI::App* command = app.add_subcommand(
      "build-vocab", "Train a vocabulary tree (hierarchical k-medians) from images");
  add_descriptor_option(command, arguments->descriptor);
  command->add_option("--branching", arguments->branching, "Children per node, k (2..255)")
      ->check(CLI::Range(2, 255))
      ->capture_default_str();
  command->add_option("--levels", arguments->levels, "Depth of the tree, L (1..16)")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  command
      ->add_option("--weighting", arguments->weighting, "Word weighting: tf-idf, tf, idf, binary")
      ->check(parsed_by(parse_weighting))
      ->capture_default_str();
  command
      ->add_option("--scoring", arguments->scoring,
                   "Scoring: l1, l2, chi-square, kl, bhattacharyya, dot-product")
      ->check(parsed_by(parse_scoring))
      ->capture_default_str();
  command->add_option("--threads", arguments->threads, "Worker threads (0: all cores)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  add_image_source_options(command, arguments->source);
  command
      ->add_option("--seed", arguments->seed,
                   "Random seed; the same seed gives the same file for any --threads")
      ->capture_default_str();
  command->add_option("--max-descriptors", arguments->max_descriptors,
                      "Train on a seeded random subset of at most N descriptors (0: all)");
  add_features_option(command, arguments->features_per_image, "--features-per-image,--features");
  command
      ->add_option("-o,--output", arguments->output,
                   std::string("Output vocabulary (.bbw, .yml.gz, ...)") + kOutputFileHelp +
                       " (as .bbw, only when redirected; the summary then goes to stderr)")
      ->required();
  command
      ->add_option("inputs", arguments->inputs,
                   "Image files, directories, videos or text lists of images")
      ->required();
  command->callback([arguments] { run_build_vocab(*arguments); });
}

}  // namespace binbow::cli
