// Transform (descriptors → BoW, + feature vector), quantisation, Hamming
// kernels and .bbw loading on a paper-sized vocabulary (k=10, L=6, 1M words),
// and transform on a trained vocabulary with real descriptors.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "bench_support.h"
#include "binbow/descriptors.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"

namespace binbow::bench {
namespace {

const Vocabulary& big_vocabulary() {
  static const Vocabulary v = full_random_vocabulary(10, 6);
  return v;
}

void BM_Transform(benchmark::State& state) {
  const Vocabulary& v = big_vocabulary();
  // Many images so that consecutive iterations do not reuse warm cache lines.
  std::vector<DescriptorMatrix> images;
  for (int i = 0; i < 64; ++i) images.push_back(random_descriptors(1000, 32, 100 + i));
  BowVector bow;
  std::size_t i = 0;
  for (auto _ : state) {
    v.transform(images[i++ % images.size()], bow);
    benchmark::DoNotOptimize(bow);
  }
  state.SetItemsProcessed(state.iterations() * 1000);
}
BENCHMARK(BM_Transform)->Unit(benchmark::kMicrosecond);

void BM_TransformWithFeatureVector(benchmark::State& state) {
  const Vocabulary& v = big_vocabulary();
  std::vector<DescriptorMatrix> images;
  for (int i = 0; i < 64; ++i) images.push_back(random_descriptors(1000, 32, 100 + i));
  BowVector bow;
  FeatureVector fv;
  std::size_t i = 0;
  for (auto _ : state) {
    v.transform(images[i++ % images.size()], bow, fv, static_cast<unsigned>(state.range(0)));
    benchmark::DoNotOptimize(fv);
  }
  state.SetItemsProcessed(state.iterations() * 1000);
}
BENCHMARK(BM_TransformWithFeatureVector)->Arg(4)->Arg(2)->Unit(benchmark::kMicrosecond);

// The realistic case: a vocabulary trained on real photographs
// (scripts/make_benchmark_vocabulary.sh; its path in BINBOW_BENCH_VOCABULARY)
// and real ORB descriptors of rtabmap-samples, a scene it was not trained on.
// The frames are taken at twice their size, their descriptors pooled in frame
// order and cut into images of 1000, each used by one call in turn.
struct Trained {
  Vocabulary vocabulary;
  std::vector<DescriptorMatrix> images;
};

const Trained* trained() {
  static const std::unique_ptr<Trained> cached = []() -> std::unique_ptr<Trained> {
    const char* path = std::getenv("BINBOW_BENCH_VOCABULARY");
    if (path == nullptr) return nullptr;
    auto t = std::make_unique<Trained>();
    t->vocabulary = Vocabulary::load(path);
    const auto extractor = vision::make_extractor("orb", 1000);
    DescriptorMatrix pool(32);
    const std::string dir = std::string(BINBOW_SHARED_DATA_DIR) + "/rtabmap-samples/samples";
    for (int frame = 1; std::filesystem::exists(dir + "/" + std::to_string(frame) + ".jpg");
         ++frame) {
      cv::Mat image = vision::read_grey_image(dir + "/" + std::to_string(frame) + ".jpg");
      cv::resize(image, image, cv::Size(), 2.0, 2.0);
      pool.append(extractor->extract(image).descriptors.view());
    }
    for (std::size_t row = 0; row + 1000 <= pool.rows(); row += 1000)
      t->images.emplace_back(pool.row(row), 1000, 32);
    return t;
  }();
  return cached.get();
}

void BM_TransformTrained(benchmark::State& state) {
  const Trained* t = trained();
  if (t == nullptr || t->images.empty()) {
    state.SkipWithError(
        "set BINBOW_BENCH_VOCABULARY to a vocabulary from scripts/make_benchmark_vocabulary.sh");
    return;
  }
  const unsigned levels_up = static_cast<unsigned>(state.range(0));
  BowVector bow;
  FeatureVector fv;
  std::size_t i = 0;
  for (auto _ : state) {
    const DescriptorMatrix& image = t->images[i++ % t->images.size()];
    if (levels_up == 0) {
      t->vocabulary.transform(image, bow);
    } else {
      t->vocabulary.transform(image, bow, fv, levels_up);
    }
    benchmark::DoNotOptimize(bow);
  }
  state.SetItemsProcessed(state.iterations() * 1000);
  state.SetLabel(std::to_string(t->vocabulary.word_count()) + " words, " +
                 (levels_up == 0 ? "BoW" : "BoW + feature vector"));
}
BENCHMARK(BM_TransformTrained)->Arg(0)->Arg(4)->Unit(benchmark::kMicrosecond);

void BM_Quantize(benchmark::State& state) {
  const Vocabulary& v = big_vocabulary();
  std::vector<DescriptorMatrix> images;
  for (int i = 0; i < 64; ++i) images.push_back(random_descriptors(1000, 32, 100 + i));
  std::vector<WordId> words(1000);
  std::size_t i = 0;
  for (auto _ : state) {
    v.quantize(images[i++ % images.size()], words.data());
    benchmark::DoNotOptimize(words.data());
  }
  state.SetItemsProcessed(state.iterations() * 1000);
}
BENCHMARK(BM_Quantize)->Unit(benchmark::kMicrosecond);

void BM_Hamming(benchmark::State& state) {
  const auto code_size = static_cast<std::size_t>(state.range(0));
  const DescriptorMatrix m = random_descriptors(1024, code_size, 7);
  std::uint32_t sum = 0;
  std::size_t i = 0;
  for (auto _ : state) {
    sum += hamming_distance(m.row(i & 1023), m.row((i + 1) & 1023), code_size);
    ++i;
  }
  benchmark::DoNotOptimize(sum);
  state.SetLabel(hamming_kernel_name());
}
BENCHMARK(BM_Hamming)->Arg(32)->Arg(64)->Arg(61);

void BM_LoadBbw(benchmark::State& state) {
  const std::string path = "/tmp/binbow-bench-" + std::to_string(getpid()) + ".bbw";
  big_vocabulary().save(path);
  LoadOptions options;
  options.verify_checksums = state.range(0) != 0;
  for (auto _ : state) {
    Vocabulary v = Vocabulary::load(path, options);
    benchmark::DoNotOptimize(v);
  }
  std::remove(path.c_str());
  state.SetLabel(options.verify_checksums ? "verify checksums" : "structure checks only");
}
BENCHMARK(BM_LoadBbw)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace binbow::bench

BENCHMARK_MAIN();
