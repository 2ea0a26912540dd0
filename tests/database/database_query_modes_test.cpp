// Query options: exact queries on several threads give the one-thread result
// bit for bit, and fast queries report only exact scores, with the exact
// best entries on data where images share most words.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "database/database_impl.h"
#include "support/query_results.h"

namespace binbow {
namespace {

using test::bits_of;
using test::expect_same_results;

constexpr QueryOptions kOneThread{QueryMode::kExact, 1};
constexpr QueryOptions kFast{QueryMode::kFast, 1};

std::uint32_t shared_words(const BowVector& a, const BowVector& b) {
  std::uint32_t shared = 0;
  for (const BowEntry& e : a)
    shared += std::binary_search(b.begin(), b.end(), e, [](const BowEntry& x, const BowEntry& y) {
      return x.word < y.word;
    });
  return shared;
}

// Every result of a fast query has the brute-force score of its entry, to
// the last bit, and the results are ordered as a query orders them.
void expect_exact_scores(const std::vector<QueryResult>& results, Scoring scoring,
                         const std::vector<BowVector>& bows, const std::vector<bool>& live,
                         const BowVector& query, EntryId max_entry_id, const std::string& context) {
  for (std::size_t i = 0; i < results.size(); ++i) {
    const QueryResult& r = results[i];
    ASSERT_LT(r.entry, bows.size()) << context;
    EXPECT_TRUE(live[r.entry]) << context << ": entry " << r.entry << " was removed";
    EXPECT_LE(r.entry, max_entry_id) << context;
    EXPECT_EQ(bits_of(r.score), bits_of(score_bow(query, bows[r.entry], scoring)))
        << context << " entry " << r.entry;
    EXPECT_EQ(r.shared_words, shared_words(query, bows[r.entry])) << context;
    if (i > 0) {
      const QueryResult& p = results[i - 1];
      const bool ordered = scoring == Scoring::kKL ? p.score <= r.score : p.score >= r.score;
      EXPECT_TRUE(ordered && (p.score != r.score || p.entry < r.entry)) << context << " rank " << i;
    }
  }
}

// Words drawn with probability ~ 1 / rank (Zipf): a few words are in most
// images, as in photographs of a few scenes, and the rest are rare.
class ZipfWords {
 public:
  ZipfWords(std::size_t word_count, std::uint64_t seed) : rng_(seed) {
    double total = 0;
    for (std::size_t w = 0; w < word_count; ++w) cumulative_.push_back(total += 1.0 / (w + 1.0));
  }
  WordId next() {
    const double u = std::uniform_real_distribution<double>(0, cumulative_.back())(rng_);
    return static_cast<WordId>(std::lower_bound(cumulative_.begin(), cumulative_.end(), u) -
                               cumulative_.begin());
  }
  std::mt19937_64& rng() { return rng_; }

 private:
  std::mt19937_64 rng_;
  std::vector<double> cumulative_;
};

// A place: its words (about `words`, Zipf-drawn) with tf-idf-like weights
// (rarer words weigh more).
std::map<WordId, float> place_words(ZipfWords& zipf, std::size_t words) {
  std::map<WordId, float> place;
  while (place.size() < words) {
    const WordId word = zipf.next();
    place[word] += std::log(2.0f + static_cast<float>(word) / 50.0f);
  }
  return place;
}

// An image of a place: each word kept with probability 0.8, plus `noise`
// random words, L1-normalised.
BowVector image_of(const std::map<WordId, float>& place, ZipfWords& zipf, std::size_t noise) {
  std::map<WordId, float> words;
  std::bernoulli_distribution keep(0.8);
  for (const auto& [word, value] : place)
    if (keep(zipf.rng())) words[word] += value;
  for (std::size_t i = 0; i < noise; ++i) {
    const WordId word = zipf.next();
    words[word] += std::log(2.0f + static_cast<float>(word) / 50.0f);
  }
  float total = 0;
  for (const auto& [word, value] : words) total += value;
  std::vector<BowEntry> entries;
  for (const auto& [word, value] : words) entries.push_back({word, value / total});
  return BowVector(std::move(entries));
}

// While alive, a query starts a thread per `postings` of the index, so that
// small indexes are split between threads as large ones are.
class ThreadsPerPostings {
 public:
  explicit ThreadsPerPostings(std::size_t postings)
      : saved_(detail::postings_per_query_thread().exchange(postings)) {}
  ~ThreadsPerPostings() { detail::postings_per_query_thread() = saved_; }

 private:
  std::size_t saved_;
};

TEST(DatabaseQueryModes, ThreadsGiveTheOneThreadResultAndBruteForce) {
  // ~1M postings (~300 words per image) in several segments, a thread per
  // 100,000 of them: a query shares its segments between threads, with ties
  // (repeated images), removals and max_entry_id. The images are made once
  // and indexed under each scoring.
  const ThreadsPerPostings split_small_indexes(100'000);
  ZipfWords zipf(60'000, 11);
  std::vector<std::map<WordId, float>> places;
  for (int p = 0; p < 100; ++p) places.push_back(place_words(zipf, 300));
  std::vector<BowVector> bows;
  for (std::size_t i = 0; i < 3'500; ++i)
    bows.push_back(i % 7 == 3 ? bows[i - 1] : image_of(places[i % places.size()], zipf, 70));
  std::vector<BowVector> queries;
  for (int q = 0; q < 6; ++q) queries.push_back(image_of(places[q * 13], zipf, 70));
  const BowVector brute_force_query = image_of(places[5], zipf, 70);

  for (Scoring scoring : {Scoring::kL1, Scoring::kKL, Scoring::kDotProduct}) {
    DatabaseOptions options;
    options.direct_index = false;
    Database database = Database::over_word_ids(scoring, options);
    std::vector<bool> live;
    for (std::size_t i = 0; i < bows.size(); ++i) {
      live.push_back(true);
      database.add(bows[i]);
      if (i % 101 == 50) {
        database.remove(static_cast<EntryId>(i / 2));
        live[i / 2] = false;
      }
    }
    for (std::size_t q = 0; q < queries.size(); ++q) {
      const BowVector& query = queries[q];
      const std::string context = std::string(to_string(scoring)) + " query " + std::to_string(q);
      const auto one = database.query(query, 30, kAllEntries, kOneThread);
      ASSERT_EQ(one.size(), 30u) << context;
      expect_exact_scores(one, scoring, bows, live, query, kAllEntries, context);
      for (unsigned threads : {0u, 2u, 3u, 8u}) {
        const QueryOptions split{QueryMode::kExact, threads};
        expect_same_results(database.query(query, 30, kAllEntries, split), one,
                            context + ", " + std::to_string(threads) + " threads");
        expect_same_results(database.query(query, 30, 1'234, split),
                            database.query(query, 30, 1'234, kOneThread),
                            context + ", max_entry_id");
      }
      expect_same_results(database.query(query, 30), one, context + ", default options");
    }
    // The one-thread result itself is the brute force's top 30.
    std::vector<QueryResult> all;
    for (EntryId e = 0; e < bows.size(); ++e) {
      if (!live[e]) continue;
      const std::uint32_t shared = shared_words(brute_force_query, bows[e]);
      if (shared > 0) all.push_back({e, score_bow(brute_force_query, bows[e], scoring), shared});
    }
    std::stable_sort(all.begin(), all.end(), [&](const QueryResult& a, const QueryResult& b) {
      return scoring == Scoring::kKL ? a.score < b.score : a.score > b.score;
    });
    all.resize(30);
    expect_same_results(
        database.query(brute_force_query, 30, kAllEntries, QueryOptions{QueryMode::kExact, 2}), all,
        std::string(to_string(scoring)) + " brute force");
  }
}

TEST(DatabaseQueryModes, FastScoresAreExactAndItsBestAreTheExactBest) {
  // Images of 100 places share most of their words (Zipf), as photographs
  // of a few scenes do; queries are new images of known places. 2,000
  // images (~130k postings per query) with a small minimum of postings and
  // 100 candidates, so that fast mode scores candidates rather than reading
  // every posting. The images are made once and indexed under each scoring.
  ZipfWords zipf(80'000, 3);
  std::vector<std::map<WordId, float>> places;
  for (int p = 0; p < 100; ++p) places.push_back(place_words(zipf, 400));
  // Entry 0 holds only a word no image has, which a query holds with a
  // weight so small that it never finds candidates: fast mode leaves the
  // entry out where an exact query of every result finds it.
  constexpr WordId kLoneWord = 80'000;
  std::vector<BowVector> bows{BowVector({{kLoneWord, 0.5f}})};
  for (std::size_t i = 1; i < 2'000; ++i)
    bows.push_back(image_of(places[i % places.size()], zipf, 150));
  const std::vector<bool> live(bows.size(), true);
  constexpr int kQueries = 60;
  std::vector<BowVector> queries;
  for (int q = 0; q < kQueries; ++q)
    queries.push_back(image_of(places[(q * 53) % places.size()], zipf, 150));
  QueryOptions fast = kFast;
  fast.fast_candidates = 100;
  fast.fast_candidate_share = 0;
  fast.fast_min_postings = 1 << 12;

  for (Scoring scoring : {Scoring::kL1, Scoring::kL2, Scoring::kChiSquare, Scoring::kKL,
                          Scoring::kBhattacharyya, Scoring::kDotProduct}) {
    DatabaseOptions options;
    options.direct_index = false;
    Database database = Database::over_word_ids(scoring, options);
    for (const BowVector& bow : bows) database.add(bow);
    const std::string name = to_string(scoring);
    int same_top10 = 0, same_place = 0, same_with_10_candidates = 0;
    for (const BowVector& query : queries) {
      const auto exact = database.query(query, 10, kAllEntries, kOneThread);
      const auto found = database.query(query, 10, kAllEntries, fast);
      ASSERT_EQ(found.size(), 10u) << name;
      expect_exact_scores(found, scoring, bows, live, query, kAllEntries, name);
      same_top10 += found == exact;
      same_place += found[0].entry % places.size() == exact[0].entry % places.size();
      QueryOptions two_threads = fast;
      two_threads.threads = 2;
      expect_same_results(database.query(query, 10, kAllEntries, two_threads), found,
                          name + ", fast on 2 threads");
      QueryOptions fewer = fast;
      fewer.fast_candidates = 10;
      fewer.fast_candidate_share = 0;
      same_with_10_candidates += database.query(query, 10, kAllEntries, fewer) == exact;
      // A share of the entries as many as fast_candidates: the same candidates.
      QueryOptions by_share = fewer;
      by_share.fast_candidates = 1;
      by_share.fast_candidate_share = 100.0 / static_cast<double>(bows.size());
      expect_same_results(database.query(query, 10, kAllEntries, by_share), found,
                          name + ", candidates by share");
    }
    EXPECT_GE(same_top10, kQueries - 1) << name;
    EXPECT_EQ(same_place, kQueries) << name;
    // The candidates' number and the rare words bound what fast mode reads.
    EXPECT_LT(same_with_10_candidates, same_top10) << name;
    std::vector<BowEntry> words(queries[0].begin(), queries[0].end());
    words.push_back({kLoneWord, 1e-9f});
    const BowVector lone(std::move(words));
    const auto has_entry_0 = [](const std::vector<QueryResult>& results) {
      return std::any_of(results.begin(), results.end(),
                         [](const QueryResult& r) { return r.entry == 0; });
    };
    EXPECT_TRUE(has_entry_0(database.query(lone, bows.size(), kAllEntries, kOneThread))) << name;
    EXPECT_FALSE(has_entry_0(database.query(lone, bows.size(), kAllEntries, fast))) << name;
  }
}

TEST(DatabaseQueryModes, FastFindsTheNewestEntriesAndRescoresEveryEntryAskedFor) {
  // 2,000 images of 40 places: the first ~1,000 become a segment, the rest
  // stay in the tail, whose entries fast mode finds as candidates too. An
  // image added last, and queried, is its own best match. Entry 0 holds
  // only a word no image has, as in the test above: a query that holds it
  // with a tiny weight finds entry 0 only when it reads every posting.
  ZipfWords zipf(80'000, 11);
  std::vector<std::map<WordId, float>> places;
  for (int p = 0; p < 40; ++p) places.push_back(place_words(zipf, 400));
  Database database = Database::over_word_ids(Scoring::kL1, DatabaseOptions{false, 0});
  constexpr WordId kLoneWord = 80'000;
  std::vector<BowVector> bows{BowVector({{kLoneWord, 0.5f}})};
  database.add(bows.back());
  for (std::size_t i = 1; i < 2'000; ++i) {
    bows.push_back(image_of(places[i % places.size()], zipf, 150));
    database.add(bows.back());
  }
  const std::vector<bool> live(bows.size(), true);
  QueryOptions few = kFast;
  few.fast_candidates = 20;
  few.fast_candidate_share = 0;
  few.fast_min_postings = 1 << 10;
  QueryOptions every = few;
  every.fast_candidate_share = 1.0;
  for (std::size_t newest = bows.size() - 5; newest < bows.size(); ++newest) {
    const BowVector& query = bows[newest];
    const auto found = database.query(query, 10, kAllEntries, few);
    ASSERT_FALSE(found.empty());
    EXPECT_EQ(found[0].entry, newest);
    expect_exact_scores(found, Scoring::kL1, bows, live, query, kAllEntries, "few candidates");
    std::vector<BowEntry> words(query.begin(), query.end());
    words.push_back({kLoneWord, 1e-9f});
    const auto with_lone =
        database.query(BowVector(std::move(words)), bows.size(), kAllEntries, few);
    ASSERT_FALSE(with_lone.empty());
    EXPECT_EQ(with_lone[0].entry, newest);
    EXPECT_TRUE(std::none_of(with_lone.begin(), with_lone.end(), [](const QueryResult& r) {
      return r.entry == 0;
    })) << "fast mode read every posting: no candidates were searched";
    // Every entry a candidate: no candidate is left out, so the results
    // are the exact ones.
    expect_same_results(database.query(query, 50, kAllEntries, every),
                        database.query(query, 50, kAllEntries, kOneThread), "every entry");
  }
}

TEST(DatabaseQueryModes, FastQueryOptionsAreChecked) {
  Database database = Database::over_word_ids(Scoring::kL1, DatabaseOptions{false, 0});
  database.add(BowVector({{1, 0.5f}}));
  QueryOptions options = kFast;
  options.fast_candidates = 0;
  EXPECT_THROW(database.query(BowVector({{1, 0.5f}}), 1, kAllEntries, options), InvalidArgument);
  EXPECT_THROW(options.check(), InvalidArgument);
  options.fast_candidates = std::numeric_limits<std::size_t>::max();
  EXPECT_NO_THROW(options.check());
  options.fast_min_postings = 0;
  EXPECT_EQ(database.query(BowVector({{1, 0.5f}}), 1, kAllEntries, options).size(), 1u);
  for (double share : {-0.5, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    QueryOptions bad = kFast;
    bad.fast_candidate_share = share;
    EXPECT_THROW(database.query(BowVector({{1, 0.5f}}), 1, kAllEntries, bad), InvalidArgument);
    EXPECT_THROW(bad.check(), InvalidArgument);
  }
  options.fast_candidate_share = 1.0;
  EXPECT_EQ(database.query(BowVector({{1, 0.5f}}), 1, kAllEntries, options).size(), 1u);
}

TEST(DatabaseQueryModes, CandidatesGrowWithTheEntriesAsTunedOrAsTheShareSet) {
  // By default N / 125 * (N / 10^6)^0.3 for N entries, and at least
  // fast_candidates: the counts docs/benchmarks.md measured at each size.
  const QueryOptions defaults;
  EXPECT_EQ(defaults.candidates_for(0), 1000u);
  EXPECT_EQ(defaults.candidates_for(10'000), 1000u);
  EXPECT_EQ(defaults.candidates_for(200'000), 1000u);
  EXPECT_EQ(defaults.candidates_for(500'000), 3250u);
  EXPECT_EQ(defaults.candidates_for(1'000'000), 8000u);
  EXPECT_EQ(defaults.candidates_for(2'000'000), 19'699u);
  QueryOptions linear = defaults;
  linear.fast_candidate_share = 1.0 / 125;
  EXPECT_EQ(linear.candidates_for(200'000), 1600u);
  EXPECT_EQ(linear.candidates_for(1'000'000), 8000u);
  linear.fast_candidate_share = 1.0;
  EXPECT_EQ(linear.candidates_for(123'456), 123'456u);
  linear.fast_candidate_share = 0.0;
  EXPECT_EQ(linear.candidates_for(1'000'000), 1000u);
  linear.fast_candidates = 5;
  EXPECT_EQ(linear.candidates_for(1'000'000), 5u);
  // Unchecked options give a count, never undefined behaviour.
  linear.fast_candidate_share = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(linear.candidates_for(1'000), 5u);
  linear.fast_candidate_share = 1e300;
  EXPECT_EQ(linear.candidates_for(1'000), 1'000u);
}

TEST(DatabaseQueryModes, FastQueriesFollowAddsRemovalsAndBounds) {
  // Fast queries keep each entry's BoW vector from the first one on: entries
  // added or removed later, and the bounds of max_entry_id, count as in
  // exact queries.
  const Scoring scoring = Scoring::kL1;
  Database database = Database::over_word_ids(scoring, DatabaseOptions{false, 0});
  ZipfWords zipf(20'000, 7);
  std::vector<std::map<WordId, float>> places;
  for (int p = 0; p < 50; ++p) places.push_back(place_words(zipf, 300));
  std::vector<BowVector> bows;
  std::vector<bool> live;
  const BowVector query = image_of(places[4], zipf, 50);
  EXPECT_TRUE(database.query(query, 10, kAllEntries, kFast).empty()) << "empty database";
  const auto add = [&](std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) {
      bows.push_back(image_of(places[bows.size() % places.size()], zipf, 50));
      live.push_back(true);
      database.add(bows.back());
    }
  };
  const auto check = [&](const std::string& context) {
    for (EntryId max_id : {kAllEntries, static_cast<EntryId>(bows.size() / 3), EntryId{0}}) {
      const auto fast = database.query(query, 1'000'000, max_id, kFast);
      expect_exact_scores(fast, scoring, bows, live, query, max_id, context);
      const auto exact = database.query(query, 1'000'000, max_id, kOneThread);
      // More results asked than there are entries: a fast query finds those
      // that share one of its rare words.
      EXPECT_LE(fast.size(), exact.size()) << context;
      EXPECT_EQ(fast.empty(), exact.empty()) << context;
      const auto fast3 = database.query(query, 3, max_id, kFast);
      expect_same_results(fast3, database.query(query, 3, max_id, kOneThread), context + ", top 3");
    }
  };
  add(700);
  check("first fast query");
  add(2'500);  // into new segments, after the first fast query
  check("after adds");
  for (EntryId e = 0; e < bows.size(); e += 3) {
    database.remove(e);
    live[e] = false;
  }
  check("after removals");
  database.add(BowVector());  // an image without words
  bows.emplace_back();
  live.push_back(true);
  check("after an empty image");
  database.clear();
  bows.clear();
  live.clear();
  EXPECT_TRUE(database.query(query, 10, kAllEntries, kFast).empty()) << "cleared";
  add(400);
  check("after clear");
  EXPECT_TRUE(database.query(BowVector(), 10, kAllEntries, kFast).empty());
  EXPECT_TRUE(database.query(query, 0, kAllEntries, kFast).empty());
}

TEST(DatabaseQueryModes, UnknownModeIsRefused) {
  Database database = Database::over_word_ids(Scoring::kL1, DatabaseOptions{false, 0});
  database.add(BowVector({{1, 0.5f}}));
  QueryOptions options;
  options.mode = static_cast<QueryMode>(7);
  EXPECT_THROW(database.query(BowVector({{1, 0.5f}}), 1, kAllEntries, options), InvalidArgument);
}

}  // namespace
}  // namespace binbow
