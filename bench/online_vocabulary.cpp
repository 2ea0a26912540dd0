// The online vocabulary at 100, 1,000 and 10,000 images of 1,000 ORB
// descriptors: add_image (search, new words, majority updates, purges, tree
// splits and rebuilds) and transform per image, and memory per word.
//
// Descriptors: the real ORB descriptors (1,000 per frame) of rtabmap-samples'
// 84 frames, replayed in order; each pass over the frames flips a fresh
// random 8% of every descriptor's bits (about 20 of 256), so later passes
// look like a similar place seen again, neither identical (the vocabulary
// would stop growing) nor unrelated. Words therefore keep growing and
// purging as in a long run in a new environment.
//
// The vocabulary is grown to N images once per size (not timed; 10,000
// images take a few minutes), then the next images are timed one by one.
// Reported: median time per image, words, and the vocabulary's heap memory
// per word and per image.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "binbow/online_vocabulary.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"

namespace binbow::bench {
namespace {

const std::vector<DescriptorMatrix>& sample_frames() {
  static const std::vector<DescriptorMatrix> frames = [] {
    const auto orb = vision::make_extractor("orb", 1000);
    std::vector<DescriptorMatrix> out;
    for (int i = 1; i <= 84; ++i) {
      const std::string path = std::string(BINBOW_SHARED_DATA_DIR) + "/rtabmap-samples/samples/" +
                               std::to_string(i) + ".jpg";
      out.push_back(orb->extract(vision::read_grey_image(path)).descriptors);
    }
    return out;
  }();
  return frames;
}

// Image `index` of the endless stream: frame index % 84, its bits flipped
// with a generator seeded by the pass, so every pass differs and every run
// is the same.
DescriptorMatrix stream_image(std::size_t index) {
  const std::vector<DescriptorMatrix>& frames = sample_frames();
  DescriptorMatrix image = frames[index % frames.size()];
  const std::size_t pass = index / frames.size();
  if (pass == 0) return image;
  std::mt19937_64 rng(pass * 1000003 + index);
  std::bernoulli_distribution flip(0.08);
  for (std::size_t i = 0; i < image.rows() * image.code_size(); ++i)
    for (int bit = 0; bit < 8; ++bit)
      if (flip(rng)) image.data()[i] ^= static_cast<std::uint8_t>(1u << bit);
  return image;
}

// A vocabulary grown to `images` images, kept for the process.
OnlineVocabulary& grown(std::size_t images) {
  static std::map<std::size_t, std::unique_ptr<OnlineVocabulary>> cache;
  auto& slot = cache[images];
  if (!slot) {
    OnlineVocabularyOptions options;
    options.descriptor = "orb";
    slot = std::make_unique<OnlineVocabulary>(32, options);
    for (std::size_t i = 0; i < images; ++i) slot->add_image(stream_image(i));
  }
  return *slot;
}

// Counters: the median time per image, the words, the memory.
void report(benchmark::State& state, const OnlineVocabulary& vocabulary,
            std::vector<double> milliseconds) {
  std::nth_element(milliseconds.begin(), milliseconds.begin() + milliseconds.size() / 2,
                   milliseconds.end());
  state.counters["median_ms"] = milliseconds[milliseconds.size() / 2];
  const OnlineVocabularyStats stats = vocabulary.stats();
  state.counters["words"] = static_cast<double>(stats.words);
  state.counters["bytes_per_word"] =
      static_cast<double>(stats.memory_bytes) / static_cast<double>(stats.words);
  state.counters["bytes_per_image"] =
      static_cast<double>(stats.memory_bytes) / static_cast<double>(stats.images);
}

void BM_OnlineAddImage(benchmark::State& state) {
  const auto images = static_cast<std::size_t>(state.range(0));
  OnlineVocabulary vocabulary = grown(images);  // a copy: each run starts alike
  std::vector<DescriptorMatrix> next;
  for (std::size_t i = 0; i < 64; ++i) next.push_back(stream_image(images + i));
  OnlineImageWords result;
  std::vector<double> milliseconds;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    vocabulary.add_image(next[i++ % next.size()], result);
    milliseconds.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
    benchmark::DoNotOptimize(result);
  }
  report(state, vocabulary, milliseconds);
}
// One iteration per image, 64 images after the first N.
BENCHMARK(BM_OnlineAddImage)
    ->Arg(100)
    ->Arg(1000)
    ->Arg(10000)
    ->Iterations(64)
    ->Unit(benchmark::kMillisecond);

void BM_OnlineTransform(benchmark::State& state) {
  const OnlineVocabulary& vocabulary = grown(static_cast<std::size_t>(state.range(0)));
  std::vector<DescriptorMatrix> queries;
  for (std::size_t i = 0; i < 16; ++i)
    queries.push_back(stream_image(static_cast<std::size_t>(state.range(0)) + 100 + i));
  BowVector bow;
  FeatureVector features;
  std::vector<double> milliseconds;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    vocabulary.transform(queries[i++ % queries.size()], bow, &features);
    milliseconds.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
    benchmark::DoNotOptimize(bow);
  }
  report(state, vocabulary, milliseconds);
}
BENCHMARK(BM_OnlineTransform)
    ->Arg(100)
    ->Arg(1000)
    ->Arg(10000)
    ->Iterations(64)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace binbow::bench

BENCHMARK_MAIN();
