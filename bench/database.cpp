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
//
// BM_Rescore times fast mode's exact scoring of a candidate from the forward
// index alone, on real images (see there).
#include <benchmark/benchmark.h>

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_support.h"
#include "binbow/database.h"
#include "core/scoring.h"
#include "database/forward_index.h"
#include "orb_photographs.h"

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

// Fast mode's rescoring: the exact score of each candidate from its copy in
// the forward index, as fast queries compute it (the L1 terms as minimums).
// Entries are noisy copies (8 of 256 bits flipped per descriptor) of the
// training photographs' ORB-1000 descriptors on the benchmark vocabulary
// (BINBOW_BENCH_VOCABULARY, as for bench_database_scale); queries are
// noisy copies of every tenth photograph, held out, as that benchmark's are.
// Each query's candidates are its exact best kRescoreCandidates entries, in
// score order, as a fast query's are (a fifth of a candidate's words are the
// query's); every score is checked against the exact query's first. The
// counter time_per_candidate is the CPU time per candidate; argument 1
// looks words up with the portable code, 0 with the CPU's fastest.
constexpr std::size_t kRescoreEntries = 16000;
constexpr std::size_t kRescoreCandidates = 1600;
constexpr int kRescoreFlippedBits = 8;

struct RescoreQuery {
  BowVector bow;
  detail::QueryWordSet words;
  std::vector<double> weights;          // ForwardIndex::word_weight of each word
  std::vector<QueryResult> candidates;  // the exact best, with their scores
};

struct RescoreSet {
  std::string error;  // why the benchmark cannot run
  Vocabulary vocabulary;
  detail::ForwardIndex forward;
  std::vector<RescoreQuery> queries;
  double words_per_entry = 0;
};

struct Rescored {
  double sum = 0;
  std::uint32_t shared = 0;
};

Rescored rescore(const RescoreSet& set, const RescoreQuery& query, EntryId entry,
                 std::vector<std::uint32_t>& hits) {
  Rescored r;
  set.forward.for_each_shared(entry, query.words, query.weights.data(), hits,
                              [&](std::uint32_t q, float weight) {
                                r.sum += std::min(query.bow[q].value, weight);
                                ++r.shared;
                              });
  return r;
}

const RescoreSet& rescore_set() {
  static const std::unique_ptr<RescoreSet> cached = [] {
    auto set = std::make_unique<RescoreSet>();
    const char* path = std::getenv("BINBOW_BENCH_VOCABULARY");
    if (path == nullptr) {
      set->error =
          "set BINBOW_BENCH_VOCABULARY to a vocabulary from "
          "scripts/make_benchmark_vocabulary.sh";
      return set;
    }
    set->vocabulary = Vocabulary::load(path);
    if (set->vocabulary.scoring() != Scoring::kL1) {
      set->error = "the benchmark vocabulary scores with L1";
      return set;
    }
    const auto extractor = vision::make_extractor("orb", static_cast<int>(kFeatures));
    std::vector<DescriptorMatrix> photographs, held_out;
    const std::vector<std::string> paths = training_photographs(false);
    for (std::size_t i = 0; i < paths.size(); ++i) {
      DescriptorMatrix descriptors = orb_descriptors(*extractor, paths[i], kFeatures);
      if (descriptors.rows() != kFeatures) continue;
      (i % 10 == 9 ? held_out : photographs).push_back(std::move(descriptors));
    }
    if (photographs.size() < 50 || held_out.empty()) {
      set->error = "too few training photographs with 1000 ORB features (" +
                   std::to_string(photographs.size()) + "): run scripts/training_images.sh";
      return set;
    }
    const auto noisy_bow = [&](const DescriptorMatrix& photograph, std::uint64_t seed) {
      DescriptorMatrix image = photograph;
      flip_bits(image, kRescoreFlippedBits, seed);
      BowVector bow;
      set->vocabulary.transform(image, bow);
      return bow;
    };
    Database database(set->vocabulary, DatabaseOptions{false, 0});
    set->forward = detail::ForwardIndex(&set->vocabulary, Scoring::kL1);
    std::size_t words = 0;
    for (std::size_t e = 0; e < kRescoreEntries; ++e) {
      const BowVector bow = noisy_bow(photographs[e % photographs.size()], e);
      database.add(bow);
      set->forward.append(Span<BowEntry>(bow.begin(), bow.size()));
      words += bow.size();
    }
    set->words_per_entry = static_cast<double>(words) / static_cast<double>(kRescoreEntries);
    std::vector<std::uint32_t> hits;
    for (std::size_t q = 0; q < held_out.size(); ++q) {
      RescoreQuery query;
      query.bow = noisy_bow(held_out[q], 0x9000000000 + q);
      query.words.assign(Span<BowEntry>(query.bow.begin(), query.bow.size()));
      for (const BowEntry& e : query.bow) query.weights.push_back(set->forward.word_weight(e.word));
      query.candidates = database.query(query.bow, kRescoreCandidates);
      for (const QueryResult& candidate : query.candidates) {
        const Rescored r = rescore(*set, query, candidate.entry, hits);
        if (detail::l1_score_of_minimums(r.sum) != candidate.score ||
            r.shared != candidate.shared_words) {
          set->error = "a rescored candidate's score differs from the exact query's";
          return set;
        }
      }
      set->queries.push_back(std::move(query));
    }
    return set;
  }();
  return *cached;
}

void BM_Rescore(benchmark::State& state) {
  const RescoreSet& set = rescore_set();
  if (!set.error.empty()) {
    state.SkipWithError(set.error.c_str());
    return;
  }
  const bool portable = state.range(0) != 0;
  detail::portable_forward_lookups() = portable;
  std::vector<std::uint32_t> hits;
  std::size_t i = 0, candidates = 0, shared = 0;
  for (auto _ : state) {
    const RescoreQuery& query = set.queries[i++ % set.queries.size()];
    double total = 0;
    for (std::size_t c = 0; c < query.candidates.size(); ++c) {
      if (c + 1 < query.candidates.size()) set.forward.prefetch(query.candidates[c + 1].entry);
      const Rescored r = rescore(set, query, query.candidates[c].entry, hits);
      total += r.sum;
      shared += r.shared;
    }
    candidates += query.candidates.size();
    benchmark::DoNotOptimize(total);
  }
  detail::portable_forward_lookups() = false;
  state.SetLabel(portable ? "portable" : "fastest for the CPU");
  state.counters["time_per_candidate"] = benchmark::Counter(
      static_cast<double>(candidates), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["shared_words"] = static_cast<double>(shared) / static_cast<double>(candidates);
  state.counters["words_per_entry"] = set.words_per_entry;
  state.counters["B_per_entry"] =
      static_cast<double>(set.forward.memory_usage()) / static_cast<double>(set.forward.size());
}
BENCHMARK(BM_Rescore)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(1.0);

}  // namespace
}  // namespace binbow::bench

BENCHMARK_MAIN();
