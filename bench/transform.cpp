// Transform (descriptors → BoW, + feature vector), quantisation, Hamming
// kernels and .bbw loading on a paper-sized vocabulary (k=10, L=6, 1M words).
#include <benchmark/benchmark.h>

#include <unistd.h>
#include <cstdio>

#include "bench_support.h"
#include "binbow/descriptors.h"

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
