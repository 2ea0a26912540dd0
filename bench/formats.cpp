// Vocabulary loading speed per format. The ORB-SLAM text file is generated in
// ORBvoc.txt's exact format from a random k=10, L=6 tree shaped like
// ORB-SLAM's 684k-word ORBvoc.txt (levels 1-5 full, 0-10 leaves under each
// depth-5 node): loading speed depends on the file's size and node count,
// not on how the words were trained. Results: docs/benchmarks.md, "Formats".
#include <benchmark/benchmark.h>

#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <random>
#include <string>

#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "core/file_io.h"
#include "formats/codecs.h"
#include "support/random_tree.h"

namespace {

using namespace binbow;

// ~690k words, ~800k nodes.
VocabularyTree orbvoc_like_tree() {
  std::mt19937_64 rng(2026);
  std::uniform_int_distribution<std::uint32_t> last_level(3, 11);  // capped at 10: mean ≈ 6.9
  return test::random_tree(10, 6, 32, rng, [&](std::uint32_t depth, std::mt19937_64& r) {
    return depth < 5 ? 10u : std::min(10u, last_level(r));
  });
}

struct Files {
  std::string dir, text, bbw, dbow3, fbow, orbslam_binary, yaml;
  std::size_t words = 0, nodes = 0, text_bytes = 0;
  Files() {
    char pattern[] = "/tmp/binbow-bench-formats-XXXXXX";
    dir = ::mkdtemp(pattern);
    text = dir + "/ORBvoc.txt";
    bbw = dir + "/ORBvoc.bbw";
    dbow3 = dir + "/ORBvoc.dbow3";
    fbow = dir + "/ORBvoc.fbow";
    orbslam_binary = dir + "/ORBvoc.bin";
    yaml = dir + "/ORBvoc.yml";
    const Vocabulary vocabulary = Vocabulary::from_tree(orbvoc_like_tree());
    words = vocabulary.word_count();
    nodes = vocabulary.node_count();
    for (const std::string* path : {&text, &bbw, &dbow3, &fbow, &orbslam_binary, &yaml})
      save_vocabulary(vocabulary, *path);
    text_bytes = detail::MappedFile(text).size();
  }
  ~Files() {
    for (const std::string* path : {&text, &bbw, &dbow3, &fbow, &orbslam_binary, &yaml})
      std::remove(path->c_str());
    ::rmdir(dir.c_str());
  }
};

const Files& files() {
  static const Files instance;
  return instance;
}

void add_counters(benchmark::State& state, std::size_t bytes) {
  state.counters["words"] = static_cast<double>(files().words);
  state.counters["MB"] = static_cast<double>(bytes) / 1e6;
  state.SetBytesProcessed(static_cast<std::int64_t>(bytes) * state.iterations());
}

void BM_LoadOrbSlamText(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(load_vocabulary(files().text));
  add_counters(state, files().text_bytes);
}

// Parsing alone (file already mapped), by thread count.
void BM_ParseOrbSlamText(benchmark::State& state) {
  const detail::MappedFile file(files().text);
  for (auto _ : state)
    benchmark::DoNotOptimize(detail::parse_orbslam_text(file.data(), file.size(), "bench",
                                                        static_cast<unsigned>(state.range(0))));
  add_counters(state, file.size());
}

void BM_SaveOrbSlamText(benchmark::State& state) {
  const Vocabulary vocabulary = load_vocabulary(files().bbw);
  const std::string out = files().dir + "/saved.txt";
  for (auto _ : state) save_vocabulary(vocabulary, out);
  add_counters(state, files().text_bytes);
  std::remove(out.c_str());
}

void BM_LoadBbw(benchmark::State& state) {
  LoadOptions options;
  options.verify_checksums = state.range(0) != 0;
  for (auto _ : state) benchmark::DoNotOptimize(Vocabulary::load(files().bbw, options));
  add_counters(state, detail::MappedFile(files().bbw).size());
}

void BM_LoadOther(benchmark::State& state, std::string Files::*path) {
  const std::string& file = files().*path;
  for (auto _ : state) benchmark::DoNotOptimize(load_vocabulary(file));
  add_counters(state, detail::MappedFile(file).size());
}

void BM_LoadDbow2YamlBriefLite(benchmark::State& state) {
  const std::string path =
      std::string(BINBOW_SHARED_DATA_DIR) + "/vins-lite-brief-vocab/brief_lite.voc.gz";
  std::size_t words = 0;
  for (auto _ : state) words = load_vocabulary(path).word_count();
  state.counters["words"] = static_cast<double>(words);
}

BENCHMARK(BM_LoadOrbSlamText)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_ParseOrbSlamText)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_SaveOrbSlamText)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_LoadBbw)
    ->Arg(1)
    ->Arg(0)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK_CAPTURE(BM_LoadOther, orbslam_binary, &Files::orbslam_binary)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK_CAPTURE(BM_LoadOther, dbow3, &Files::dbow3)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK_CAPTURE(BM_LoadOther, fbow, &Files::fbow)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK_CAPTURE(BM_LoadOther, dbow2_yaml, &Files::yaml)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_LoadDbow2YamlBriefLite)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
