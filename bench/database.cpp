// Image database: add (BoW and level-4 direct index given) and top-10 queries
// at 1k / 10k / 100k entries on the paper-sized vocabulary (k=10, L=6, 1M
// words), with the heap memory per entry.
//
// Images are 1000 descriptors transformed with the vocabulary, in two regimes:
//   uniform: random descriptors, words spread evenly over the 1M leaves
//            (short posting lists: the easy case);
//   skewed:  noisy copies of a pool of "world" descriptors picked with a
//            heavily skewed popularity, so some words recur in many images
//            and posting lists are long, as with real images.
// 4000 images are transformed once and reused cyclically to fill larger
// databases: query cost depends on posting list lengths, which grow with N
// exactly as they would with distinct images of the same word statistics.
#include <benchmark/benchmark.h>

#include <malloc.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "bench_support.h"
#include "binbow/database.h"

namespace binbow::bench {
namespace {

constexpr std::size_t kPoolImages = 4000;
constexpr std::size_t kQueryImages = 200;
constexpr std::size_t kFeatures = 1000;
constexpr unsigned kLevelsUp = 4;

const Vocabulary& big_vocabulary() {
  static const Vocabulary v = full_random_vocabulary(10, 6);
  return v;
}

struct Images {
  std::vector<BowVector> bows;
  std::vector<FeatureVector> features;
  std::vector<BowVector> queries;
};

DescriptorMatrix make_image(bool skewed, std::mt19937_64& rng, const DescriptorMatrix& world) {
  DescriptorMatrix image(kFeatures, 32);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (std::size_t r = 0; r < kFeatures; ++r) {
    std::uint8_t* row = image.row(r);
    if (!skewed) {
      for (std::size_t b = 0; b < 32; ++b) row[b] = static_cast<std::uint8_t>(rng());
      continue;
    }
    const auto pick =
        static_cast<std::size_t>(static_cast<double>(world.rows()) * std::pow(uniform(rng), 3.0));
    std::memcpy(row, world.row(pick), 32);
    for (int flip = 0; flip < 8; ++flip) {
      const auto bit = rng() % 256;
      row[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    }
  }
  return image;
}

const Images& images(bool skewed) {
  static std::unique_ptr<Images> cache[2];
  auto& slot = cache[skewed ? 1 : 0];
  if (slot) return *slot;
  slot = std::make_unique<Images>();
  const DescriptorMatrix world = random_descriptors(50000, 32, 7);
  std::mt19937_64 rng(skewed ? 11 : 12);
  const Vocabulary& vocabulary = big_vocabulary();
  for (std::size_t i = 0; i < kPoolImages + kQueryImages; ++i) {
    const DescriptorMatrix image = make_image(skewed, rng, world);
    BowVector bow;
    FeatureVector features;
    vocabulary.transform(image.view(), bow, features, kLevelsUp);
    if (i < kPoolImages) {
      slot->bows.push_back(std::move(bow));
      slot->features.push_back(std::move(features));
    } else {
      slot->queries.push_back(std::move(bow));
    }
  }
  return *slot;
}

std::size_t heap_in_use() {
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;  // small blocks + mmapped large blocks
}

struct BuiltDatabase {
  bool skewed = false;
  std::size_t entries = 0;
  std::size_t heap_bytes = 0;  // malloc'd bytes the database holds, allocator overhead included
  std::unique_ptr<Database> database;
};

// One database at a time (the 100k one holds about a gigabyte).
const BuiltDatabase& database(bool skewed, std::size_t entries) {
  static BuiltDatabase built;
  if (built.database && built.skewed == skewed && built.entries == entries) return built;
  built.database.reset();
  const Images& pool = images(skewed);
  const std::size_t before = heap_in_use();
  built.database = std::make_unique<Database>(big_vocabulary(), DatabaseOptions{true, kLevelsUp});
  for (std::size_t i = 0; i < entries; ++i)
    built.database->add(pool.bows[i % kPoolImages], pool.features[i % kPoolImages]);
  built.heap_bytes = heap_in_use() - before;
  built.skewed = skewed;
  built.entries = entries;
  return built;
}

void BM_Add(benchmark::State& state) {
  const bool skewed = state.range(0) != 0;
  const Images& pool = images(skewed);
  Database db(big_vocabulary(), DatabaseOptions{true, kLevelsUp});
  std::size_t i = 0;
  for (auto _ : state) {
    db.add(pool.bows[i % kPoolImages], pool.features[i % kPoolImages]);
    if (++i % 10000 == 0) {
      state.PauseTiming();
      db.clear();
      state.ResumeTiming();
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(skewed ? "skewed" : "uniform");
}
// Exactly one fill from empty to 10k entries per run, so every run pays the
// same segment builds (an automatic iteration count would stop at an
// arbitrary size).
BENCHMARK(BM_Add)->Arg(0)->Arg(1)->Iterations(10000)->Unit(benchmark::kMicrosecond);

void BM_Query(benchmark::State& state) {
  const bool skewed = state.range(0) != 0;
  const auto entries = static_cast<std::size_t>(state.range(1));
  const BuiltDatabase& built = database(skewed, entries);
  const Images& pool = images(skewed);
  std::size_t i = 0, candidates = 0;
  for (auto _ : state) {
    const auto results = built.database->query(pool.queries[i++ % kQueryImages], 10);
    candidates += results.size();
    benchmark::DoNotOptimize(results.data());
  }
  state.SetLabel(skewed ? "skewed" : "uniform");
  state.counters["entries"] = static_cast<double>(entries);
  state.counters["KiB/entry(heap)"] =
      static_cast<double>(built.heap_bytes) / 1024.0 / static_cast<double>(entries);
  state.counters["KiB/entry(index)"] =
      static_cast<double>(built.database->memory_usage()) / 1024.0 / static_cast<double>(entries);
}
BENCHMARK(BM_Query)
    ->ArgsProduct({{0, 1}, {1000, 10000, 100000}})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(0.5);

}  // namespace
}  // namespace binbow::bench

BENCHMARK_MAIN();
