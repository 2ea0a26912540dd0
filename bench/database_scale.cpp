// The image database at scale: 10k → 100k → 200k → 500k → 1M entries of real images on the
// trained k=10 L=6 ORB vocabulary (scripts/make_benchmark_vocabulary.sh; its
// path in BINBOW_BENCH_VOCABULARY, as for bench_transform).
//
// Images: OpenCV ORB-1000 descriptors of the Debian training photographs
// (scripts/training_images.sh --all). Every tenth photograph is held out for
// the queries; each database entry is one of the others with kFlippedBits
// random bits flipped in every descriptor (seeded per entry), so that entries
// are distinct images of the same scenes, then transformed (BoW vector and
// feature vector 4 levels up) and added at once: only one entry's descriptors
// exist at a time, however large the database grows. Queries are the
// held-out photographs with their own noise: images not in the database.
//
// The benchmarks run in order on one growing database: BM_Fill/N adds entries
// until there are N (the time is the add calls alone: their mean is the
// counter add_us), BM_Query/N answers the queries (top 10: exact on one
// thread and on every core, and fast; see there), BM_FastCandidates/N fast
// mode's agreement against its candidates on other queries (also at
// 500,000, between the sizes the others measure),
// BM_QueryBounds/200000 measures what pruned or stop-listed queries would
// read (see there), BM_Save/N measures full and incremental
// saves, the disk's write rate and opening (see there), and BM_SaveLoad saves the largest database
// to a .bbdb file (in BINBOW_BENCH_DIR, default /tmp; deleted afterwards), frees it, loads it back
// and checks that the loaded database answers every query identically, with the peak resident
// memory of each step over the database's memory.
//
// BINBOW_BENCH_SCALE_DIRECT_INDEX=0 measures a database without direct index
// (a retrieval server); the loop detector needs one (the default).
// BINBOW_BENCH_SCALE_MAX_ENTRIES (default 1,000,000) stops the growth early.
#include <benchmark/benchmark.h>

#include <malloc.h>
#include <unistd.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "binbow/database.h"
#include "binbow/vision/features.h"
#include "orb_photographs.h"

namespace binbow::bench {
namespace {

constexpr std::size_t kFeatures = 1000;
constexpr unsigned kLevelsUp = 4;
constexpr int kFlippedBits = 8;  // of 256 per descriptor
constexpr std::size_t kMaxResults = 10;
constexpr std::size_t kNoisyCopiesPerQuery = 2;
constexpr std::size_t kTuningCopiesPerQuery = 4;

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// This thread's CPU time: the machine is shared, and other processes inflate
// wall times (both are reported).
double thread_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec) * 1e-9;
}

std::size_t heap_in_use() {
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;  // small blocks + mmapped large blocks
}

// Resident memory now and its peak since the last reset_peak_rss(), in bytes.
std::size_t status_kib(const std::string& field) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind(field + ":", 0) == 0) return std::stoul(line.substr(field.size() + 1));
  return 0;
}
std::size_t rss() {
  return status_kib("VmRSS") * 1024;
}
std::size_t peak_rss() {
  return status_kib("VmHWM") * 1024;
}
bool reset_peak_rss() {
  std::ofstream clear_refs("/proc/self/clear_refs");
  clear_refs << "5";
  clear_refs.flush();
  return static_cast<bool>(clear_refs);
}

struct Scale {
  Vocabulary vocabulary;
  bool direct_index = true;
  std::size_t max_entries = 1000000;
  std::string folder = "/tmp";
  std::vector<DescriptorMatrix> photographs;  // the database's sources
  std::vector<BowVector> queries;
  // Postings a query reads per database entry, on average (the median query's
  // cost is about this times the entries): the queries' words weighted by how
  // many of the photographs, without noise, have them.
  double postings_per_entry = 0;
  std::unique_ptr<Database> database;
  std::size_t heap_before = 0;  // heap in use before the database was created
  double words_per_entry = 0;   // distinct words of the entries added, mean
  std::size_t words_total = 0;
  // Per word, over the entries added: how many have it, and its largest
  // weight in any of them (what a pruned query could bound a word's part by).
  std::vector<std::uint32_t> entries_with_word;
  std::vector<float> largest_weight;
  // Other noisy copies of the held-out photographs, for choosing fast
  // mode's defaults apart from the reported queries (BM_FastCandidates).
  std::vector<BowVector> tuning_queries;
};

// Null (with the reason in `error`) when the vocabulary or the photographs
// are missing.
Scale* scale(std::string& error) {
  static std::string failure;
  static const std::unique_ptr<Scale> cached = []() -> std::unique_ptr<Scale> {
    const char* vocabulary = std::getenv("BINBOW_BENCH_VOCABULARY");
    if (vocabulary == nullptr) {
      failure =
          "set BINBOW_BENCH_VOCABULARY to a vocabulary from "
          "scripts/make_benchmark_vocabulary.sh";
      return nullptr;
    }
    auto s = std::make_unique<Scale>();
    s->vocabulary = Vocabulary::load(vocabulary);
    if (const char* direct = std::getenv("BINBOW_BENCH_SCALE_DIRECT_INDEX"))
      s->direct_index = std::string(direct) != "0";
    if (const char* max = std::getenv("BINBOW_BENCH_SCALE_MAX_ENTRIES"))
      s->max_entries = std::stoul(max);
    if (const char* folder = std::getenv("BINBOW_BENCH_DIR")) s->folder = folder;
    const std::vector<std::string> paths = training_photographs(true);
    const auto extractor = vision::make_extractor("orb", static_cast<int>(kFeatures));
    for (std::size_t i = 0; i < paths.size(); ++i) {
      DescriptorMatrix descriptors = orb_descriptors(*extractor, paths[i], kFeatures);
      if (descriptors.rows() != kFeatures) continue;
      if (i % 10 != 9) {
        s->photographs.push_back(std::move(descriptors));
        continue;
      }
      // Noisy copies of the held-out photograph, seeded apart per set.
      const auto add_copies = [&](std::uint64_t seed_base, std::size_t copies,
                                  std::vector<BowVector>& out) {
        for (std::size_t copy = 0; copy < copies; ++copy) {
          DescriptorMatrix query = descriptors;
          flip_bits(query, kFlippedBits, seed_base + i * copies + copy);
          BowVector bow;
          s->vocabulary.transform(query, bow);
          out.push_back(std::move(bow));
        }
      };
      add_copies(0xA000000000, kTuningCopiesPerQuery, s->tuning_queries);
      add_copies(0x9000000000, kNoisyCopiesPerQuery, s->queries);
    }
    std::vector<std::uint32_t> photographs_with_word(s->vocabulary.word_count(), 0);
    for (const DescriptorMatrix& photograph : s->photographs) {
      BowVector bow;
      s->vocabulary.transform(photograph, bow);
      for (const BowEntry& entry : bow) ++photographs_with_word[entry.word];
    }
    for (const BowVector& query : s->queries)
      for (const BowEntry& entry : query)
        s->postings_per_entry += photographs_with_word[entry.word];
    s->postings_per_entry /=
        static_cast<double>(s->queries.size()) * static_cast<double>(s->photographs.size());
    if (s->photographs.size() < 100 || s->queries.empty()) {
      failure = "too few training photographs with 1000 ORB features (" +
                std::to_string(s->photographs.size()) + "): run scripts/training_images.sh --all";
      return nullptr;
    }
    s->entries_with_word.assign(s->vocabulary.word_count(), 0);
    s->largest_weight.assign(s->vocabulary.word_count(), 0.0f);
    s->heap_before = heap_in_use();
    s->database =
        std::make_unique<Database>(s->vocabulary, DatabaseOptions{s->direct_index, kLevelsUp});
    return s;
  }();
  error = failure;
  return cached.get();
}

Scale* scale_or_skip(benchmark::State& state) {
  std::string error;
  Scale* s = scale(error);
  if (s == nullptr) state.SkipWithError(error.c_str());
  return s;
}

// The scale, when BM_Fill has made the database as large as the benchmark's
// argument.
Scale* filled_scale_or_skip(benchmark::State& state) {
  Scale* s = scale_or_skip(state);
  if (s != nullptr && s->database->size() != static_cast<std::size_t>(state.range(0))) {
    state.SkipWithError("run after BM_Fill of the same size");
    return nullptr;
  }
  return s;
}

// How often fast results agree with exact ones: the same top 10, and a copy
// of the same photograph first (entry ids cycle through the photographs).
struct Agreement {
  double same_top10 = 0;
  double same_place = 0;
};

Agreement agreement(const std::vector<std::vector<QueryResult>>& exact,
                    const std::vector<std::vector<QueryResult>>& fast, std::size_t places) {
  Agreement shares;
  for (std::size_t q = 0; q < exact.size(); ++q) {
    shares.same_top10 += fast[q] == exact[q] ? 1 : 0;
    shares.same_place += !exact[q].empty() && !fast[q].empty() &&
                                 fast[q][0].entry % places == exact[q][0].entry % places
                             ? 1
                             : 0;
  }
  shares.same_top10 /= static_cast<double>(exact.size());
  shares.same_place /= static_cast<double>(exact.size());
  return shares;
}

void label(benchmark::State& state, const Scale& s) {
  state.SetLabel(std::to_string(s.vocabulary.word_count()) + " words, " +
                 std::to_string(s.photographs.size()) + " photographs, " +
                 (s.direct_index ? "direct index" : "no direct index"));
}

void memory_counters(benchmark::State& state, const Scale& s) {
  const auto entries = static_cast<double>(s.database->size());
  state.counters["entries"] = entries;
  state.counters["bytes_per_entry"] = static_cast<double>(s.database->memory_usage()) / entries;
  state.counters["KiB/entry(index)"] =
      static_cast<double>(s.database->memory_usage()) / 1024.0 / entries;
  state.counters["KiB/entry(heap)"] =
      static_cast<double>(heap_in_use() - s.heap_before) / 1024.0 / entries;
  state.counters["words/entry"] =
      static_cast<double>(s.words_total) / static_cast<double>(s.database->next_entry_id());
}

// Adds entries until the database's next id is `target`; the time spent in
// add() alone is added to the totals.
void add_entries(Scale& s, std::size_t target, double& add_seconds, double& add_cpu_seconds) {
  DescriptorMatrix image;
  BowVector bow;
  FeatureVector features;
  for (std::size_t entry = s.database->next_entry_id(); entry < target; ++entry) {
    image = s.photographs[entry % s.photographs.size()];
    flip_bits(image, kFlippedBits, entry);
    if (s.direct_index) {
      s.vocabulary.transform(image, bow, features, kLevelsUp);
    } else {
      s.vocabulary.transform(image, bow);
    }
    s.words_total += bow.size();
    for (const BowEntry& word : bow) {
      ++s.entries_with_word[word.word];
      s.largest_weight[word.word] = std::max(s.largest_weight[word.word], word.value);
    }
    const Clock::time_point start = Clock::now();
    const double cpu_start = thread_seconds();
    s.database->add(bow, features);
    add_cpu_seconds += thread_seconds() - cpu_start;
    add_seconds += seconds_since(start);
  }
}

void BM_Fill(benchmark::State& state) {
  Scale* s = scale_or_skip(state);
  if (s == nullptr) return;
  const auto target = static_cast<std::size_t>(state.range(0));
  if (target > s->max_entries) {
    state.SkipWithError("above BINBOW_BENCH_SCALE_MAX_ENTRIES");
    return;
  }
  for (auto _ : state) {
    const std::size_t first = s->database->next_entry_id();
    double add_seconds = 0, add_cpu_seconds = 0;
    add_entries(*s, target, add_seconds, add_cpu_seconds);
    state.SetIterationTime(add_seconds);
    state.counters["add_us"] = add_seconds * 1e6 / static_cast<double>(target - first);
    state.counters["add_us_cpu"] = add_cpu_seconds * 1e6 / static_cast<double>(target - first);
  }
  memory_counters(state, *s);
  label(state, *s);
}

// Wall and CPU milliseconds of each query, and its results.
struct TimedQueries {
  std::vector<double> wall, cpu;
  std::vector<std::vector<QueryResult>> results;
};

void time_query(const Database& database, const BowVector& query, const QueryOptions& options,
                TimedQueries& timed) {
  const Clock::time_point start = Clock::now();
  const double cpu_start = thread_seconds();
  timed.results.push_back(database.query(query, kMaxResults, kAllEntries, options));
  timed.cpu.push_back((thread_seconds() - cpu_start) * 1e3);
  timed.wall.push_back(seconds_since(start) * 1e3);
}

double median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

double percentile90(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() * 9 / 10];
}

// Whether every entry that both lists hold has the same score and shared
// words in both: fast mode's scores are exact.
bool same_scores(const std::vector<QueryResult>& a, const std::vector<QueryResult>& b) {
  for (const QueryResult& x : a)
    for (const QueryResult& y : b)
      if (x.entry == y.entry && !(x == y)) return false;
  return true;
}

// At each size: exact queries on one thread (query_ms) and on every core
// (query_threads_ms, which must give the same results), then fast mode
// (query_fast_ms) and what it loses: the share of queries whose top 10 is
// the exact top 10 (fast_same_top10), and whose first result is a copy of
// the same photograph as the exact first (fast_same_place_top1). Times are
// wall-clock medians of the 148 queries (_cpu: this thread's CPU time). Each
// query runs in the three ways in turn before the next one, so that the
// three medians see the same load on a shared machine (blocks of 148 queries
// each saw a different one). The first fast query copies every entry's BoW
// vector (and add keeps copying), so memory counters include that copy from
// the first BM_Query on.
void BM_Query(benchmark::State& state) {
  Scale* s = filled_scale_or_skip(state);
  if (s == nullptr) return;
  for (auto _ : state) {
    TimedQueries exact_timed, threaded, fast_timed;
    for (const BowVector& query : s->queries) {
      time_query(*s->database, query, QueryOptions{QueryMode::kExact, 1}, exact_timed);
      time_query(*s->database, query, QueryOptions{}, threaded);
      time_query(*s->database, query, QueryOptions{QueryMode::kFast, 1}, fast_timed);
    }
    const auto& exact = exact_timed.results;
    const auto& fast_results = fast_timed.results;
    if (threaded.results != exact) {
      state.SkipWithError("queries on several threads answer differently");
      return;
    }
    for (std::size_t q = 0; q < exact.size(); ++q)
      if (!same_scores(exact[q], fast_results[q])) {
        state.SkipWithError("a fast query's score differs from the exact query's");
        return;
      }
    const Agreement shares = agreement(exact, fast_results, s->photographs.size());
    state.counters["query_ms"] = median(exact_timed.wall);
    state.counters["query_ms_cpu"] = median(exact_timed.cpu);
    state.counters["query_ms_p90"] = percentile90(exact_timed.wall);
    state.counters["query_threads_ms"] = median(threaded.wall);
    state.counters["query_fast_ms"] = median(fast_timed.wall);
    state.counters["query_fast_ms_cpu"] = median(fast_timed.cpu);
    state.counters["query_fast_ms_p90"] = percentile90(fast_timed.wall);
    state.counters["fast_same_top10"] = shares.same_top10;
    state.counters["fast_same_place_top1"] = shares.same_place;
    state.counters["threads"] = static_cast<double>(std::thread::hardware_concurrency());
    state.counters["postings/query"] =
        s->postings_per_entry * static_cast<double>(s->database->size());
  }
  memory_counters(state, *s);
  label(state, *s);
}
// Why an exact query reads every posting of these images, and what skipping
// the most common words (Sivic & Zisserman's stop list) would cost. For each
// query, with the exact 10th score θ known in advance (an oracle):
// - maxscore_read: the share of its postings in the words that an exact
//   MaxScore-style query must read in full, all but the words of least
//   bound min(query weight, largest weight) whose bounds sum below θ (L1);
// - stop<f>_read: the share left when words in more than a fraction f of the
//   entries are dropped from the query, and stop<f>_same_top: how often its
//   best entry is still a copy of the same photograph as the exact best.
void BM_QueryBounds(benchmark::State& state) {
  Scale* s = scale_or_skip(state);
  if (s == nullptr) return;
  if (s->database->size() != static_cast<std::size_t>(state.range(0)) ||
      s->database->scoring() != Scoring::kL1) {
    state.SkipWithError("run after BM_Fill of the same size, with an L1 vocabulary");
    return;
  }
  const auto entries = static_cast<double>(s->database->size());
  const double fractions[] = {0.2, 0.1, 0.05};
  for (auto _ : state) {
    std::vector<double> maxscore_read;
    std::vector<double> stop_read[3], stop_same_top[3];
    for (const BowVector& query : s->queries) {
      const auto exact =
          s->database->query(query, kMaxResults, kAllEntries, {QueryMode::kExact, 1});
      if (exact.size() < kMaxResults) continue;
      const double theta = exact.back().score;
      std::vector<std::pair<double, std::uint32_t>> bounds;  // (bound, postings)
      double postings = 0;
      for (const BowEntry& word : query) {
        bounds.emplace_back(std::min(word.value, s->largest_weight[word.word]),
                            s->entries_with_word[word.word]);
        postings += s->entries_with_word[word.word];
      }
      std::sort(bounds.begin(), bounds.end());
      double bound_sum = 0, skipped = 0;
      for (const auto& [bound, word_postings] : bounds) {
        if (bound_sum + bound >= theta) break;
        bound_sum += bound;
        skipped += word_postings;
      }
      maxscore_read.push_back(1.0 - skipped / postings);
      for (std::size_t f = 0; f < 3; ++f) {
        std::vector<BowEntry> kept;
        double kept_postings = 0;
        for (const BowEntry& word : query)
          if (s->entries_with_word[word.word] <= fractions[f] * entries) {
            kept.push_back(word);
            kept_postings += s->entries_with_word[word.word];
          }
        const auto pruned =
            s->database->query(BowVector(std::move(kept)), 1, kAllEntries, {QueryMode::kExact, 1});
        stop_read[f].push_back(kept_postings / postings);
        stop_same_top[f].push_back(!pruned.empty() && pruned[0].entry % s->photographs.size() ==
                                                          exact[0].entry % s->photographs.size());
      }
    }
    const auto mean = [](const std::vector<double>& values) {
      double sum = 0;
      for (double v : values) sum += v;
      return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
    };
    state.counters["maxscore_read"] = median(maxscore_read);
    const char* names[] = {"stop0.2", "stop0.1", "stop0.05"};
    for (std::size_t f = 0; f < 3; ++f) {
      state.counters[std::string(names[f]) + "_read"] = median(stop_read[f]);
      state.counters[std::string(names[f]) + "_same_top"] = mean(stop_same_top[f]);
    }
  }
  label(state, *s);
}

std::size_t file_size(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return 0;
  std::fseek(file, 0, SEEK_END);
  const long size = std::ftell(file);
  std::fclose(file);
  return size < 0 ? 0 : static_cast<std::size_t>(size);
}

// Seconds to write `bytes` to a new file at `path` in 1 MiB writes, then
// fdatasync it: the disk's sequential write rate as a save meets it.
double write_scratch_file(const std::string& path, std::size_t bytes) {
  std::vector<char> block(std::size_t{1} << 20);
  std::mt19937_64 rng(1);
  for (char& c : block) c = static_cast<char>(rng());
  const Clock::time_point start = Clock::now();
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return 0;
  for (std::size_t done = 0; done < bytes; done += block.size())
    std::fwrite(block.data(), 1, std::min(block.size(), bytes - done), file);
  std::fflush(file);
  fdatasync(fileno(file));
  std::fclose(file);
  const double seconds = seconds_since(start);
  std::remove(path.c_str());
  return seconds;
}

// Saving and opening at each size, in BINBOW_BENCH_DIR:
// - save_full_s: a full save (Database::save, fsync'ed), and its rate
//   save_full_mb_s; disk_write_mb_s: the rate of writing a scratch file of
//   about the same size in the same folder, then fdatasync, measured right
//   before and right after the save (their mean; save_full/disk is the
//   save's rate over it);
// - save_incremental_s: Database::save_incremental after adding 1% more
//   entries (the journal's size in journal_MB);
// - open_to_first_query_s: from Database::load (base and journal, warm page
//   cache) to the first query's answer; the loaded database replaces the one
//   in memory and must answer every query as it did;
// - open_to_verified_s: from Database::load to the end of the background
//   check of the mapped file (Database::wait_until_verified);
// - open_to_first_query_s_cpu: the CPU time of the thread that opens and
//   queries (the background check's thread excluded);
// - loaded_bytes_per_entry: memory_usage() per entry of the loaded database,
//   whose rows and direct index are the mapped file's pages.
void BM_Save(benchmark::State& state) {
  Scale* s = filled_scale_or_skip(state);
  if (s == nullptr) return;
  const std::string path = s->folder + "/binbow-bench-save-" + std::to_string(getpid()) + ".bbdb";
  for (auto _ : state) {
    // The disk's rate before and after the save (other jobs share it): their mean.
    const std::size_t expected_bytes = static_cast<std::size_t>(s->database->memory_usage() * 0.98);
    const double disk_before = write_scratch_file(path + ".scratch", expected_bytes);
    Clock::time_point start = Clock::now();
    const double cpu_start = thread_seconds();
    s->database->save(path, false);
    const double full_seconds = seconds_since(start);
    const double full_cpu_seconds = thread_seconds() - cpu_start;
    const std::size_t base_bytes = file_size(path);
    const double disk_after = write_scratch_file(path + ".scratch", base_bytes);
    const double disk_mb_s = (static_cast<double>(expected_bytes) / disk_before +
                              static_cast<double>(base_bytes) / disk_after) /
                             2e6;

    const std::size_t target = s->database->next_entry_id() + s->database->size() / 100;
    double add_seconds = 0, add_cpu_seconds = 0;
    add_entries(*s, target, add_seconds, add_cpu_seconds);
    start = Clock::now();
    s->database->save_incremental(path, false);
    const double incremental_seconds = seconds_since(start);
    const std::size_t journal_bytes = file_size(Database::journal_path(path));

    std::vector<std::vector<QueryResult>> expected;
    for (const BowVector& query : s->queries)
      expected.push_back(s->database->query(query, kMaxResults, {QueryMode::kExact, 1}));
    s->database.reset();
    malloc_trim(0);
    start = Clock::now();
    const double open_cpu_start = thread_seconds();
    s->database = std::make_unique<Database>(Database::load(path, s->vocabulary));
    const auto first = s->database->query(s->queries.front(), kMaxResults, {QueryMode::kExact, 1});
    const double open_seconds = seconds_since(start);
    const double open_cpu_seconds = thread_seconds() - open_cpu_start;
    s->database->wait_until_verified();
    const double verified_seconds = seconds_since(start);
    const double loaded_bytes_per_entry =
        static_cast<double>(s->database->memory_usage()) / static_cast<double>(s->database->size());
    std::remove(path.c_str());
    std::remove(Database::journal_path(path).c_str());
    for (std::size_t q = 0; q < s->queries.size(); ++q)
      if (s->database->query(s->queries[q], kMaxResults, {QueryMode::kExact, 1}) != expected[q]) {
        state.SkipWithError("the database loaded from base and journal answers differently");
        return;
      }

    const double mb = static_cast<double>(base_bytes) / 1e6;
    state.SetIterationTime(full_seconds);
    state.counters["save_full_s"] = full_seconds;
    state.counters["save_full_s_cpu"] = full_cpu_seconds;
    state.counters["save_full_mb_s"] = mb / full_seconds;
    state.counters["disk_write_mb_s"] = disk_mb_s;
    state.counters["save_full/disk"] = mb / full_seconds / disk_mb_s;
    state.counters["save_incremental_s"] = incremental_seconds;
    state.counters["journal_MB"] = static_cast<double>(journal_bytes) / 1e6;
    state.counters["file_MB"] = mb;
    state.counters["open_to_first_query_s"] = open_seconds;
    state.counters["open_to_verified_s"] = verified_seconds;
    state.counters["open_to_first_query_s_cpu"] = open_cpu_seconds;
    state.counters["loaded_bytes_per_entry"] = loaded_bytes_per_entry;
  }
  label(state, *s);
}

// Registered size by size: each size's queries run before the database grows on.
// Fast mode's agreement and time against its number of candidates, on the
// tuning queries (not the reported ones): top10_<c> and place_<c> as
// fast_same_top10 and fast_same_place_top1, ms_<c> the median CPU time of
// one query with c candidates; exact_ms the exact query's.
void BM_FastCandidates(benchmark::State& state) {
  Scale* s = filled_scale_or_skip(state);
  if (s == nullptr) return;
  for (auto _ : state) {
    // Query by query, as BM_Query: every count sees the same load.
    const std::size_t counts[] = {800, 1000, 2000, 2500, 3000, 5000, 6000, 8000};
    TimedQueries exact;
    std::vector<TimedQueries> found(std::size(counts));
    for (const BowVector& query : s->tuning_queries) {
      time_query(*s->database, query, QueryOptions{QueryMode::kExact, 1}, exact);
      for (std::size_t k = 0; k < std::size(counts); ++k) {
        QueryOptions fast{QueryMode::kFast, 1};
        fast.fast_candidates = counts[k];
        fast.fast_candidate_share = 0;
        time_query(*s->database, query, fast, found[k]);
      }
    }
    state.counters["exact_ms"] = median(exact.cpu);
    for (std::size_t k = 0; k < std::size(counts); ++k) {
      const Agreement shares = agreement(exact.results, found[k].results, s->photographs.size());
      const std::string c = std::to_string(counts[k]);
      state.counters["top10_" + c] = shares.same_top10;
      state.counters["place_" + c] = shares.same_place;
      state.counters["ms_" + c] = median(found[k].cpu);
    }
  }
  label(state, *s);
}

BENCHMARK(BM_Fill)->Arg(10000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK(BM_Query)->Arg(10000)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Save)->Arg(10000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK(BM_Fill)->Arg(100000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK(BM_Query)->Arg(100000)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Save)->Arg(100000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK(BM_Fill)->Arg(200000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK(BM_Query)->Arg(200000)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FastCandidates)->Arg(200000)->Iterations(1)->Unit(benchmark::kSecond);
BENCHMARK(BM_QueryBounds)->Arg(200000)->Iterations(1)->Unit(benchmark::kSecond);
BENCHMARK(BM_Save)->Arg(200000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
// The candidates fast mode needs at a size between (QueryOptions::candidates_for).
BENCHMARK(BM_Fill)->Arg(500000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK(BM_FastCandidates)->Arg(500000)->Iterations(1)->Unit(benchmark::kSecond);
BENCHMARK(BM_Fill)->Arg(1000000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK(BM_Query)->Arg(1000000)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FastCandidates)->Arg(1000000)->Iterations(1)->Unit(benchmark::kSecond);
BENCHMARK(BM_Save)->Arg(1000000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

void BM_SaveLoad(benchmark::State& state) {
  Scale* s = scale_or_skip(state);
  if (s == nullptr) return;
  const std::string path = s->folder + "/binbow-bench-scale-" + std::to_string(getpid()) + ".bbdb";
  for (auto _ : state) {
    std::vector<std::vector<QueryResult>> expected;
    for (const BowVector& query : s->queries)
      expected.push_back(s->database->query(query, kMaxResults));
    const std::size_t database_bytes = s->database->memory_usage();
    const auto entries = static_cast<double>(s->database->size());

    malloc_trim(0);
    const std::size_t rss_before_save = rss();
    if (!reset_peak_rss()) {
      state.SkipWithError("cannot reset the peak RSS (/proc/self/clear_refs)");
      return;
    }
    Clock::time_point start = Clock::now();
    s->database->save(path, false);
    const double save_seconds = seconds_since(start);
    const std::size_t save_peak = peak_rss();

    s->database.reset();
    malloc_trim(0);
    const std::size_t rss_before_load = rss();
    reset_peak_rss();
    start = Clock::now();
    s->database = std::make_unique<Database>(Database::load(path, s->vocabulary));
    const double load_seconds = seconds_since(start);
    const std::size_t load_peak = peak_rss();
    std::FILE* file = std::fopen(path.c_str(), "rb");
    std::fseek(file, 0, SEEK_END);
    const auto file_bytes = static_cast<double>(std::ftell(file));
    std::fclose(file);
    std::remove(path.c_str());

    for (std::size_t q = 0; q < s->queries.size(); ++q)
      if (s->database->query(s->queries[q], kMaxResults) != expected[q]) {
        state.SkipWithError("the loaded database answers differently");
        return;
      }
    state.SetIterationTime(save_seconds + load_seconds);
    state.counters["save_s"] = save_seconds;
    state.counters["load_s"] = load_seconds;
    state.counters["file_B/entry"] = file_bytes / entries;
    // The peak resident memory over the database's own (Database::memory_usage).
    const auto db = static_cast<double>(database_bytes);
    state.counters["save_peak/db"] =
        static_cast<double>(save_peak - std::min(save_peak, rss_before_save)) / db + 1.0;
    state.counters["load_peak/db"] =
        static_cast<double>(load_peak - std::min(load_peak, rss_before_load)) / db;
    state.counters["db_GiB"] = db / (1u << 30);
  }
  label(state, *s);
}
BENCHMARK(BM_SaveLoad)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

}  // namespace
}  // namespace binbow::bench

BENCHMARK_MAIN();
