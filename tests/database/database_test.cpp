// Database queries against brute force (the vocabulary's pairwise score over
// every entry), for all six scorings, with ties, bounds and removals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "database/database_impl.h"
#include "support/query_results.h"
#include "support/random_tree.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::bits_of;
using test::expect_same_results;

constexpr Scoring kAllScorings[] = {
    Scoring::kL1,        Scoring::kL2, Scoring::kChiSquare, Scoring::kKL, Scoring::kBhattacharyya,
    Scoring::kDotProduct};

// A small vocabulary (k=5, L=3, at most 125 words) so images share many words.
Vocabulary small_vocabulary(Weighting weighting, std::uint64_t seed = 1) {
  std::mt19937_64 rng(seed);
  std::vector<DescriptorMatrix> images;
  for (int i = 0; i < 20; ++i) images.push_back(test::clustered_descriptors(60, 32, 40, 0.08, rng));
  std::vector<DescriptorView> views;
  for (const auto& image : images) views.push_back(image.view());
  BuildOptions options;
  options.branching = 5;
  options.levels = 3;
  options.weighting = weighting;
  options.seed = seed;
  options.threads = 1;
  return Vocabulary::build(views, options);
}

struct Corpus {
  std::vector<DescriptorMatrix> images;
  std::vector<BowVector> bows;
};

Corpus random_corpus(const Vocabulary& vocabulary, std::size_t count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> rows(1, 50);
  Corpus corpus;
  for (std::size_t i = 0; i < count; ++i) {
    corpus.images.push_back(test::clustered_descriptors(rows(rng), 32, 40, 0.08, rng));
    BowVector bow;
    vocabulary.transform(corpus.images.back().view(), bow);
    corpus.bows.push_back(std::move(bow));
  }
  return corpus;
}

std::size_t shared_words(const BowVector& a, const BowVector& b) {
  std::size_t shared = 0;
  for (const BowEntry& e : a)
    if (std::binary_search(b.begin(), b.end(), e,
                           [](const BowEntry& x, const BowEntry& y) { return x.word < y.word; }))
      ++shared;
  return shared;
}

// Scores every live entry that shares a word with the query, sorts best first
// (lowest first for KL), ties by entry id.
std::vector<QueryResult> brute_force(Scoring scoring, const std::vector<BowVector>& bows,
                                     const std::vector<bool>& live, const BowVector& query,
                                     std::size_t max_results, EntryId max_entry_id = kAllEntries) {
  std::vector<QueryResult> all;
  for (EntryId id = 0; id < bows.size() && id <= max_entry_id; ++id) {
    if (!live[id]) continue;
    const std::size_t shared = shared_words(query, bows[id]);
    if (shared == 0) continue;
    all.push_back({id, score_bow(query, bows[id], scoring), static_cast<std::uint32_t>(shared)});
  }
  const bool lower_better = scoring == Scoring::kKL;
  std::stable_sort(all.begin(), all.end(), [&](const QueryResult& a, const QueryResult& b) {
    return lower_better ? a.score < b.score : a.score > b.score;
  });
  if (all.size() > max_results) all.resize(max_results);
  return all;
}

std::vector<QueryResult> brute_force(const Vocabulary& vocabulary,
                                     const std::vector<BowVector>& bows,
                                     const std::vector<bool>& live, const BowVector& query,
                                     std::size_t max_results, EntryId max_entry_id = kAllEntries) {
  return brute_force(vocabulary.scoring(), bows, live, query, max_results, max_entry_id);
}

class DatabaseScoringTest : public ::testing::TestWithParam<std::tuple<Scoring, Weighting>> {};

TEST_P(DatabaseScoringTest, QueriesEqualBruteForce) {
  const auto [scoring, weighting] = GetParam();
  const Vocabulary vocabulary = small_vocabulary(weighting).with_scoring(scoring);
  const Corpus corpus = random_corpus(vocabulary, 150, 7);
  Database database(vocabulary, {false, 0});
  for (std::size_t i = 0; i < corpus.bows.size(); ++i)
    ASSERT_EQ(database.add(corpus.bows[i]), static_cast<EntryId>(i));
  std::vector<bool> live(corpus.bows.size(), true);

  const Corpus queries = random_corpus(vocabulary, 25, 99);
  std::size_t non_trivial = 0;
  for (const BowVector& query : queries.bows) {
    for (std::size_t max_results : {std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
      const auto expected = brute_force(vocabulary, corpus.bows, live, query, max_results);
      non_trivial += expected.size() > 1;
      expect_same_results(database.query(query, max_results), expected,
                          std::string(to_string(scoring)) + "/" + to_string(weighting));
    }
    for (EntryId max_id : {EntryId{0}, EntryId{10}, EntryId{77}, EntryId{149}, EntryId{5000}})
      expect_same_results(database.query(query, 10, max_id),
                          brute_force(vocabulary, corpus.bows, live, query, 10, max_id),
                          "max_entry_id");
  }
  EXPECT_GE(non_trivial, 40u) << "the corpus must produce real rankings";
}

INSTANTIATE_TEST_SUITE_P(AllScorings, DatabaseScoringTest,
                         ::testing::Combine(::testing::ValuesIn(kAllScorings),
                                            ::testing::Values(Weighting::kTfIdf, Weighting::kTf,
                                                              Weighting::kIdf,
                                                              Weighting::kBinary)));

TEST(Database, TiesAreOrderedByEntryId) {
  for (Scoring scoring : kAllScorings) {
    const Vocabulary vocabulary = small_vocabulary(Weighting::kBinary).with_scoring(scoring);
    const Corpus corpus = random_corpus(vocabulary, 40, 3);
    Database database(vocabulary);
    std::vector<BowVector> bows;
    // Entries 0..39 are the corpus, then every third image again three times:
    // exact duplicates must come back in increasing id order.
    for (const BowVector& bow : corpus.bows) bows.push_back(bow);
    for (int copy = 0; copy < 3; ++copy)
      for (std::size_t i = 0; i < corpus.bows.size(); i += 3) bows.push_back(corpus.bows[i]);
    for (const BowVector& bow : bows) database.add(bow);
    std::vector<bool> live(bows.size(), true);
    for (std::size_t i = 0; i < corpus.bows.size(); i += 3) {
      const auto results = database.query(corpus.bows[i], 1000);
      expect_same_results(results, brute_force(vocabulary, bows, live, corpus.bows[i], 1000),
                          to_string(scoring));
      // The query itself and its three copies score the same, in id order.
      std::vector<EntryId> copies;
      for (const auto& r : results)
        if (r.score == results[0].score) copies.push_back(r.entry);
      EXPECT_TRUE(std::is_sorted(copies.begin(), copies.end())) << to_string(scoring);
    }
  }
}

TEST(Database, BinaryDotProductTiesEverywhere) {
  // Binary weights with the dot product give integer scores: ties galore.
  const Vocabulary vocabulary =
      small_vocabulary(Weighting::kBinary).with_scoring(Scoring::kDotProduct);
  const Corpus corpus = random_corpus(vocabulary, 300, 11);
  Database database(vocabulary, {false, 0});
  for (const BowVector& bow : corpus.bows) database.add(bow);
  std::vector<bool> live(corpus.bows.size(), true);
  for (std::size_t q = 0; q < 20; ++q)
    for (std::size_t n : {std::size_t{3}, std::size_t{50}})
      expect_same_results(database.query(corpus.bows[q], n),
                          brute_force(vocabulary, corpus.bows, live, corpus.bows[q], n), "dot");
}

TEST(Database, RemovedEntriesNeverAppear) {
  for (Scoring scoring : {Scoring::kL1, Scoring::kKL}) {
    const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf).with_scoring(scoring);
    const Corpus corpus = random_corpus(vocabulary, 200, 5);
    Database database(vocabulary);
    for (const BowVector& bow : corpus.bows) database.add(bow);
    std::vector<bool> live(corpus.bows.size(), true);
    std::mt19937_64 rng(17);
    // Remove in rounds so that compaction happens between queries.
    for (int round = 0; round < 6; ++round) {
      for (int k = 0; k < 25; ++k) {
        const EntryId victim = static_cast<EntryId>(rng() % corpus.bows.size());
        if (!live[victim]) {
          EXPECT_THROW(database.remove(victim), InvalidArgument);
          continue;
        }
        database.remove(victim);
        live[victim] = false;
        EXPECT_FALSE(database.contains(victim));
        EXPECT_THROW(database.feature_vector(victim), InvalidArgument);
      }
      EXPECT_EQ(database.size(),
                static_cast<std::size_t>(std::count(live.begin(), live.end(), true)));
      for (std::size_t q = 0; q < 30; ++q) {
        const auto results = database.query(corpus.bows[q], 1000);
        for (const auto& r : results) EXPECT_TRUE(live[r.entry]) << r.entry;
        expect_same_results(results,
                            brute_force(vocabulary, corpus.bows, live, corpus.bows[q], 1000),
                            "after removal");
      }
    }
    // Ids are never reused.
    EXPECT_EQ(database.add(corpus.bows[0]), static_cast<EntryId>(corpus.bows.size()));
  }
}

// Picks one of the entries below `count` at random and removes it if it is
// still there.
void remove_one_of(Database& database, std::vector<bool>& live, std::size_t count,
                   std::mt19937_64& rng) {
  const auto victim = static_cast<EntryId>(rng() % count);
  if (!live[victim]) return;
  database.remove(victim);
  live[victim] = false;
}

TEST(Database, QueriesAcrossSegmentsAndTail) {
  // Enough postings (the vocabulary has 125 words, so the tail becomes a
  // segment every 65,536 postings) for several segments while entries keep
  // being added and removed, some of them from segments.
  for (Scoring scoring : {Scoring::kL1, Scoring::kKL, Scoring::kChiSquare}) {
    const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf).with_scoring(scoring);
    const Corpus corpus = random_corpus(vocabulary, 6000, 21);
    Database database(vocabulary, {false, 0});
    std::vector<bool> live(corpus.bows.size(), false);
    std::mt19937_64 rng(4);
    std::size_t checks = 0;
    for (std::size_t i = 0; i < corpus.bows.size(); ++i) {
      database.add(corpus.bows[i]);
      live[i] = true;
      if (i % 7 == 3) remove_one_of(database, live, i + 1, rng);
      if (i % 1500 == 1499 || i + 1 == corpus.bows.size()) {
        for (std::size_t q = 0; q < 5; ++q) {
          const BowVector& query = corpus.bows[rng() % corpus.bows.size()];
          for (EntryId max_id : {kAllEntries, static_cast<EntryId>(i / 2)})
            expect_same_results(database.query(query, 20, max_id),
                                brute_force(vocabulary, corpus.bows, live, query, 20, max_id),
                                std::string("segments and tail ") + to_string(scoring));
          ++checks;
        }
      }
    }
    EXPECT_EQ(checks, 20u);
  }
}

// A complete k-ary tree: word ids 0..k^levels-1, enough words for sparse
// tail lists, without training. Its weights do not matter: the tests that
// use it give their own BoW vectors.
Vocabulary wide_vocabulary(std::uint32_t k, std::uint32_t levels, Scoring scoring) {
  return Vocabulary::from_tree(test::complete_random_tree(k, levels, 32, 3)).with_scoring(scoring);
}

TEST(Database, ManySegmentsOfSparseAndDenseImages) {
  // 10,000 words: the tail becomes a segment every 65,536 postings, about
  // 300 images, and every 8 segments merge, so there are segments of two
  // levels. Images mix rare words (rows of one posting, most words absent
  // from a segment) with a few very common ones (long rows). Removals drop
  // postings from the tail, thin segments out until they are compacted.
  // Queries are checked as segments come and go and after a save/load.
  for (Scoring scoring : {Scoring::kL1, Scoring::kKL}) {
    const Vocabulary vocabulary = wide_vocabulary(10, 4, scoring);
    ASSERT_EQ(vocabulary.word_count(), 10000u);
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<float> value(0.01f, 1.0f);
    std::vector<BowVector> bows;
    for (int i = 0; i < 2500; ++i) {
      std::vector<bool> used(vocabulary.word_count(), false);
      const std::size_t rare = 50 + rng() % 300;
      for (std::size_t j = 0; j < rare; ++j) used[rng() % used.size()] = true;
      for (WordId common = 0; common < 40; ++common) used[common * 250] = rng() % 4 != 0;
      std::vector<BowEntry> entries;
      for (WordId w = 0; w < used.size(); ++w)
        if (used[w]) entries.push_back({w, value(rng)});
      bows.emplace_back(std::move(entries));
    }
    Database database(vocabulary, {false, 0});
    std::vector<bool> live(bows.size(), false);
    std::size_t checks = 0;
    for (std::size_t i = 0; i < bows.size(); ++i) {
      ASSERT_EQ(database.add(bows[i]), static_cast<EntryId>(i));
      live[i] = true;
      if (i % 5 == 2) remove_one_of(database, live, i + 1, rng);
      if (i % 211 == 0 || i + 1 == bows.size()) {
        const BowVector& query = bows[rng() % bows.size()];
        for (EntryId max_id : {kAllEntries, static_cast<EntryId>(i / 3)})
          expect_same_results(
              database.query(query, 15, max_id),
              brute_force(vocabulary, bows, live, query, 15, max_id),
              std::string("many segments ") + to_string(scoring) + " after " + std::to_string(i));
        ++checks;
      }
    }
    EXPECT_EQ(checks, 13u);
    const std::vector<std::uint8_t> bytes = database.serialize(false);
    const Database loaded = Database::deserialize(bytes.data(), bytes.size(), "memory", vocabulary);
    for (std::size_t q = 0; q < 10; ++q) {
      const BowVector& query = bows[rng() % bows.size()];
      expect_same_results(loaded.query(query, 15), brute_force(vocabulary, bows, live, query, 15),
                          "loaded");
    }
  }
}

// Random distinct words, sorted, with random values: an image of a big
// vocabulary without the cost of transforming descriptors.
BowVector random_bow(std::size_t words, std::size_t word_count, std::mt19937_64& rng) {
  std::uniform_real_distribution<float> value(0.01f, 1.0f);
  std::vector<WordId> ids;
  while (ids.size() < words) ids.push_back(static_cast<WordId>(rng() % word_count));
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<BowEntry> entries;
  for (WordId w : ids) entries.push_back({w, value(rng)});
  return BowVector(std::move(entries));
}

TEST(Database, OverWordIdsGrowsItsRowsAndQueriesEqualBruteForce) {
  // Word ids arrive as an online vocabulary makes them: each image draws its
  // words from all ids so far, and the ids grow from 1,000 to 600,000, so the
  // rows grow past 65,536 (where they stop being in word order) and double
  // several times with frozen segments, merged ones and a tail to re-lay.
  // Queries also name ids no entry has yet.
  for (Scoring scoring : {Scoring::kL1, Scoring::kKL, Scoring::kDotProduct}) {
    std::mt19937_64 rng(5);
    DatabaseOptions options;
    options.direct_index = false;
    Database database = Database::over_word_ids(scoring, options);
    EXPECT_TRUE(database.vocabulary().empty());
    EXPECT_EQ(database.scoring(), scoring);
    std::vector<BowVector> bows;
    std::vector<bool> live;
    constexpr std::size_t kImages = 1200;
    for (std::size_t i = 0; i < kImages; ++i) {
      const std::size_t ids = 1000 + i * 500;
      bows.push_back(random_bow(250, ids, rng));
      live.push_back(true);
      ASSERT_EQ(database.add(bows.back()), i);
      if (i % 97 == 0 && live[i / 2]) {
        database.remove(static_cast<EntryId>(i / 2));
        live[i / 2] = false;
      }
      if (i % 150 == 149) {
        const BowVector query = random_bow(300, ids + 50'000, rng);
        const std::string context =
            std::string(to_string(scoring)) + " after image " + std::to_string(i);
        expect_same_results(database.query(query, 25), brute_force(scoring, bows, live, query, 25),
                            context);
        expect_same_results(
            database.query(query, 25, static_cast<EntryId>(i / 3)),
            brute_force(scoring, bows, live, query, 25, static_cast<EntryId>(i / 3)),
            context + ", max_entry_id");
      }
    }
  }
}

// Rows of 1-byte gaps (word 0 in every image, word 2 in every other) and of
// 2-byte gaps (word 1 every 300 images); removing 1100 images in a row widens
// word 0's gap there to 1100 when the loaded segment is compacted. Queries
// equal brute force before and after, cut by max_entry_id too, and each
// save loads (the reader refuses rows wider than their gaps need).
TEST(Database, RowsOfOneAndTwoByteGaps) {
  DatabaseOptions options;
  options.direct_index = false;
  Database database = Database::over_word_ids(Scoring::kL1, options);
  std::vector<BowVector> bows;
  std::vector<bool> live;
  for (std::size_t i = 0; i < 3000; ++i) {
    std::vector<BowEntry> entries{{0, 0.25f + static_cast<float>(i % 7) / 16}};
    if (i % 300 == 0) entries.push_back({1, 0.5f});
    if (i % 2 == 0) entries.push_back({2, 0.125f});
    entries.push_back({static_cast<WordId>(3 + i % 50), 0.25f});
    bows.emplace_back(entries);
    live.push_back(true);
    database.add(bows.back());
  }
  const BowVector query({{0, 0.5f}, {1, 0.25f}, {2, 0.125f}, {10, 0.125f}});
  const auto expect_brute_force = [&](const Database& d, const std::string& context) {
    expect_same_results(d.query(query, 40), brute_force(Scoring::kL1, bows, live, query, 40),
                        context);
    expect_same_results(d.query(query, 40, 1700),
                        brute_force(Scoring::kL1, bows, live, query, 40, 1700),
                        context + ", max_entry_id");
  };
  expect_brute_force(database, "built");
  std::vector<std::uint8_t> bytes = database.serialize();
  Database loaded = Database::deserialize(bytes.data(), bytes.size(), "gaps.bbdb");
  expect_brute_force(loaded, "loaded");
  for (EntryId id = 1000; id < 2100; ++id) {
    loaded.remove(id);
    live[id] = false;
  }
  expect_brute_force(loaded, "compacted");
  bytes = loaded.serialize();
  expect_brute_force(Database::deserialize(bytes.data(), bytes.size(), "gaps.bbdb"), "reloaded");
}

// A vector in the form transform gives: float(word_weight(w) * count /
// divisor), the divisor the norm of the weight(w) * count that the scoring
// normalises by (L1 for the others, 1 for the dot product).
BowVector counted_bow_of(const Vocabulary& vocabulary, const std::vector<WordId>& ids,
                         std::uint32_t most, std::mt19937_64& rng) {
  std::vector<double> raw;
  double norm = 0;
  for (WordId w : ids) {
    const std::uint32_t count = rng() % 3 == 0 ? 1 + static_cast<std::uint32_t>(rng() % most) : 1;
    raw.push_back(static_cast<double>(vocabulary.word_weight(w)) * count);
    norm += vocabulary.scoring() == Scoring::kL2 ? raw.back() * raw.back() : raw.back();
  }
  if (vocabulary.scoring() == Scoring::kL2) norm = std::sqrt(norm);
  if (vocabulary.scoring() == Scoring::kDotProduct) norm = 1;
  std::vector<BowEntry> entries;
  for (std::size_t i = 0; i < ids.size(); ++i)
    entries.push_back({ids[i], static_cast<float>(raw[i] / norm)});
  return BowVector(std::move(entries));
}
// The same of about `words` random words.
BowVector counted_bow(const Vocabulary& vocabulary, std::size_t words, std::uint32_t most,
                      std::mt19937_64& rng) {
  std::vector<WordId> ids;
  while (ids.size() < words) ids.push_back(static_cast<WordId>(rng() % vocabulary.word_count()));
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return counted_bow_of(vocabulary, ids, most, rng);
}

TEST(Database, CountRowsAndWeightRowsEqualBruteForce) {
  // Vectors in transform's form keep counts in segment rows; hand-made ones,
  // those with a count above 255 keep f32 weights, and
  // rows mixing both keep weights. Through freezes, merges, removals
  // (compaction), saves and loads, scores equal brute force bit for bit.
  for (Scoring scoring : {Scoring::kL1, Scoring::kL2, Scoring::kChiSquare, Scoring::kDotProduct}) {
    const Vocabulary vocabulary = wide_vocabulary(10, 4, scoring);
    std::mt19937_64 rng(17);
    std::vector<BowVector> bows;
    std::size_t counted = 0;
    for (int i = 0; i < 2500; ++i) {
      const std::size_t words = 20 + rng() % 200;
      if (i % 5 == 3)
        bows.push_back(random_bow(words, vocabulary.word_count(), rng));
      else
        bows.push_back(counted_bow(vocabulary, words, i % 97 == 0 ? 400 : 12, rng));
      detail::CountForm form;
      const bool in_count_form =
          form.find(vocabulary, scoring, Span<BowEntry>(bows.back().begin(), bows.back().size()));
      counted += in_count_form && form.largest_count() <= 255 ? 1 : 0;
    }
    ASSERT_GE(counted, 1800u) << to_string(scoring);
    std::vector<bool> live(bows.size(), true);
    Database database(vocabulary, {false, 0});
    const auto expect_brute_force = [&](const Database& d, const std::string& context) {
      for (int q = 0; q < 4; ++q) {
        const BowVector& query = bows[(q * 611 + 5) % bows.size()];
        for (EntryId max_id : {kAllEntries, EntryId{1234}})
          expect_same_results(d.query(query, 30, max_id),
                              brute_force(vocabulary, bows, live, query, 30, max_id),
                              context + " " + to_string(scoring));
      }
    };
    for (const BowVector& bow : bows) database.add(bow);
    expect_brute_force(database, "added");
    for (EntryId id = 0; id < 2000; id += 2) {
      database.remove(id);
      live[id] = false;
    }
    expect_brute_force(database, "compacted");
    std::vector<std::uint8_t> bytes = database.serialize(false);
    Database loaded = Database::deserialize(bytes.data(), bytes.size(), "counts.bbdb", vocabulary);
    expect_brute_force(loaded, "loaded");
    EXPECT_EQ(loaded.serialize(false), bytes);
    for (EntryId id = 1; id < 1500; id += 4) {
      loaded.remove(id);
      live[id] = false;
    }
    expect_brute_force(loaded, "loaded, compacted");
    bytes = loaded.serialize(false);
    expect_brute_force(Database::deserialize(bytes.data(), bytes.size(), "counts.bbdb", vocabulary),
                       "reloaded");
  }
}

TEST(Database, CountRowsOfWholeSegmentsCutAnywhere) {
  // 70,000 images of 8 words out of 300 merge into segments of 65,536 ids
  // whose count rows run through all of them; queries are cut at entries
  // throughout the first segment and past it.
  for (Scoring scoring : {Scoring::kL1, Scoring::kL2}) {
    const Vocabulary vocabulary = wide_vocabulary(10, 4, scoring);
    std::mt19937_64 rng(23);
    std::vector<BowVector> bows;
    for (int i = 0; i < 70'000; ++i) {
      std::vector<WordId> ids;
      while (ids.size() < 8) ids.push_back(static_cast<WordId>(rng() % 300 * 31));
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
      bows.push_back(counted_bow_of(vocabulary, ids, 5, rng));
    }
    Database database(vocabulary, {false, 0});
    for (const BowVector& bow : bows) database.add(bow);
    const std::vector<bool> live(bows.size(), true);
    for (int q = 0; q < 3; ++q) {
      const BowVector& query = bows[rng() % bows.size()];
      for (EntryId max_id : {EntryId{9000}, EntryId{16383}, EntryId{16384}, EntryId{30000},
                             EntryId{50000}, EntryId{65535}, EntryId{65536}, kAllEntries})
        expect_same_results(database.query(query, 20, max_id),
                            brute_force(vocabulary, bows, live, query, 20, max_id),
                            std::string("whole segments ") + to_string(scoring) + ", up to " +
                                std::to_string(max_id));
    }
  }
}

TEST(Database, CountRowsTakeLessMemory) {
  // The same postings as counts (2-3 bytes each) and as weights (5-6).
  const Vocabulary vocabulary = wide_vocabulary(10, 4, Scoring::kL1);
  std::mt19937_64 rng(3);
  Database counts(vocabulary, {false, 0});
  Database weights(vocabulary, {false, 0});
  for (int i = 0; i < 3000; ++i) {
    const BowVector bow = counted_bow(vocabulary, 200, 4, rng);
    counts.add(bow);
    std::vector<BowEntry> entries(bow.begin(), bow.end());
    for (BowEntry& e : entries) e.value = std::nextafter(e.value, 1.0f);
    weights.add(BowVector(std::move(entries)));
  }
  EXPECT_LT(counts.memory_usage() + 3000 * 200 * 25 / 10, weights.memory_usage());
}

TEST(Database, OverWordIdsHasNoVocabularyToTransform) {
  Database database = Database::over_word_ids(Scoring::kL1);
  std::mt19937_64 rng(1);
  const DescriptorMatrix descriptors = test::random_descriptors(10, 32, rng);
  EXPECT_THROW(database.add(descriptors), InvalidArgument);
  database.add(random_bow(20, 100, rng));
  // Nodes of the direct index are the caller's ids (words), kept as given.
  const NodeId word = 70'000;
  const FeatureVector features = FeatureVector::from_assignment(&word, 1);
  BowVector bow(std::vector<BowEntry>{{word, 1.0f}});
  const EntryId entry = database.add(bow, features);
  EXPECT_EQ(database.feature_vector(entry), features);
  EXPECT_EQ(database.query(bow, 5).size(), 1u);
}

// The .bbdb writer lists each part's rows by walking the row order; the
// reader places them with row(): the walk must visit every word once, in
// rows 0, 1, 2, ... as row() numbers them.
TEST(Database, RowOrderWalkIsTheInverseOfRow) {
  for (const std::size_t words : {std::size_t{1}, std::size_t{10}, std::size_t{65535},
                                  std::size_t{65536}, std::size_t{65537}, std::size_t{540788}}) {
    const detail::RowOrder order(words);
    std::vector<std::uint8_t> seen(words, 0);
    std::uint32_t expected_row = 0;
    bool in_order = true;
    detail::RowOrder::for_each_row(words, [&](std::uint32_t row, WordId word) {
      in_order = in_order && row == expected_row++ && word < words && seen[word] == 0 &&
                 order.row(word) == row;
      if (word < words) seen[word] = 1;
    });
    EXPECT_TRUE(in_order) << words << " words";
    EXPECT_EQ(expected_row, words);
  }
}

TEST(Database, SegmentsOfAVocabularyOfMoreThan65536Words) {
  // 100,000 words: the tail groups words w and w + 65,536 in one list, and
  // becomes a segment every 200,000 postings (about 280 images), so 2,600
  // images make 8 segments that merge, then more. Some words are common,
  // on both sides of a group boundary.
  const Vocabulary vocabulary = wide_vocabulary(10, 5, Scoring::kL1);
  ASSERT_EQ(vocabulary.word_count(), 100000u);
  std::mt19937_64 rng(12);
  std::vector<BowVector> bows;
  for (int i = 0; i < 2600; ++i) {
    BowVector bow = random_bow(700, vocabulary.word_count(), rng);
    std::vector<BowEntry> entries(bow.begin(), bow.end());
    for (WordId w = 65530; w < 65545; ++w)  // both sides of a group boundary
      if (rng() % 2 == 0) entries.push_back({w, 0.5f});
    for (WordId w : {WordId{0}, WordId{65536}, WordId{99999}})
      if (rng() % 3 == 0) entries.push_back({w, 0.25f});
    std::sort(entries.begin(), entries.end(),
              [](const BowEntry& a, const BowEntry& b) { return a.word < b.word; });
    entries.erase(
        std::unique(entries.begin(), entries.end(),
                    [](const BowEntry& a, const BowEntry& b) { return a.word == b.word; }),
        entries.end());
    bows.emplace_back(std::move(entries));
  }
  Database database(vocabulary, {false, 0});
  std::vector<bool> live(bows.size(), false);
  const auto check = [&](const std::string& context) {
    for (int q = 0; q < 3; ++q) {
      const BowVector& query = bows[rng() % bows.size()];
      for (EntryId max_id : {kAllEntries, static_cast<EntryId>(rng() % bows.size())})
        expect_same_results(database.query(query, 12, max_id),
                            brute_force(vocabulary, bows, live, query, 12, max_id), context);
    }
  };
  for (std::size_t i = 0; i < bows.size(); ++i) {
    database.add(bows[i]);
    live[i] = true;
    if (i % 400 == 399) check("after " + std::to_string(i + 1) + " images");
  }
  // Thin out the merged segment until it is compacted, several times, and
  // the tail.
  for (EntryId id = 0; id < bows.size(); ++id) {
    if (id % 97 == 0 || (id < 2000 && id % 2 == 0)) continue;
    database.remove(id);
    live[id] = false;
    if (id % 500 == 0) check("after removing up to " + std::to_string(id));
  }
  check("after removals");
  const std::vector<std::uint8_t> bytes = database.serialize(false);
  const Database loaded = Database::deserialize(bytes.data(), bytes.size(), "memory", vocabulary);
  for (int q = 0; q < 3; ++q) {
    const BowVector& query = bows[rng() % bows.size()];
    expect_same_results(loaded.query(query, 12), brute_force(vocabulary, bows, live, query, 12),
                        "loaded");
  }
}

TEST(Database, SegmentsOfManySmallImages) {
  // Images of 0-2 words: the tail becomes a segment when it spans 65,536
  // ids (entries are 16-bit offsets in a segment), and such segments never
  // merge (they would span more). Removing every image of one segment drops
  // it.
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  std::mt19937_64 rng(5);
  std::vector<BowVector> bows;
  const std::size_t count = 10 * 65536 + 100;
  for (std::size_t i = 0; i < count; ++i)
    bows.push_back(i % 61 == 0 ? random_bow(2, vocabulary.word_count(), rng) : BowVector());
  Database database(vocabulary, {false, 0});
  std::vector<bool> live(bows.size(), true);
  for (std::size_t i = 0; i < count; ++i) {
    database.add(bows[i]);
    if (i == 3 * 65536) {
      // The second segment goes, one image at a time.
      for (EntryId id = 65536; id < 2 * 65536; ++id) {
        database.remove(id);
        live[id] = false;
      }
    }
  }
  const auto check = [&](const std::string& context) {
    for (int q = 0; q < 4; ++q) {
      const BowVector& query = bows[61 * (rng() % (count / 61))];
      for (EntryId max_id : {kAllEntries, EntryId{600000}, EntryId{70000}})
        expect_same_results(database.query(query, 30, max_id),
                            brute_force(vocabulary, bows, live, query, 30, max_id),
                            context + ", up to " + std::to_string(max_id));
    }
  };
  check("small images");
  EXPECT_EQ(database.size(), count - 65536);
  // Then the merged segment loses enough images to be compacted.
  for (EntryId id = 0; id < 4 * 65536; ++id) {
    if (!live[id]) continue;
    database.remove(id);
    live[id] = false;
  }
  check("small images, after removals");
}

TEST(Database, RemovingAnImageWithoutWordsWhoseSegmentWasDropped) {
  // The first segment (65,536 ids, the tail's limit) holds one image with
  // words; removing it drops the segment, whose images without words stay
  // alive: removing one of them used to look for its segment before the first.
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  std::mt19937_64 rng(8);
  Database database(vocabulary, {false, 0});
  const BowVector words = random_bow(3, vocabulary.word_count(), rng);
  database.add(words);
  for (std::size_t i = 1; i < 2 * 65536 + 10; ++i)
    database.add(i == 65536 + 5 ? words : BowVector());
  database.remove(0);
  database.remove(7);
  EXPECT_FALSE(database.contains(7));
  const auto results = database.query(words, 5);
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].entry, 65536u + 5);
}

TEST(Database, LoadedDatabasesAreSegmentsOf16BitEntries) {
  // A loaded database of more than 65,536 entries is one segment per 65,536
  // ids, so its postings cost what they did before saving (6 bytes, not 8),
  // and answers the same, also when queries stop inside a segment.
  const Vocabulary vocabulary = wide_vocabulary(10, 4, Scoring::kL1);
  std::mt19937_64 rng(9);
  std::vector<BowVector> bows;
  const std::size_t count = 3 * 65536 + 1000;
  for (std::size_t i = 0; i < count; ++i)
    bows.push_back(random_bow(1 + i % 20, vocabulary.word_count(), rng));
  Database database(vocabulary, {false, 0});
  std::vector<bool> live(count, true);
  for (const BowVector& bow : bows) database.add(bow);
  for (EntryId id = 100; id < count; id += 7) {
    database.remove(id);
    live[id] = false;
  }
  const std::vector<std::uint8_t> bytes = database.serialize(false);
  const Database loaded = Database::deserialize(bytes.data(), bytes.size(), "memory", vocabulary);
  EXPECT_LE(loaded.memory_usage(), database.memory_usage() * 21 / 20);
  for (int q = 0; q < 5; ++q) {
    const BowVector& query = bows[rng() % count];
    for (EntryId max_id : {kAllEntries, EntryId{150000}, EntryId{65535}, EntryId{65536}})
      expect_same_results(loaded.query(query, 20, max_id),
                          brute_force(vocabulary, bows, live, query, 20, max_id),
                          "loaded, up to " + std::to_string(max_id));
  }
}

TEST(Database, LoadedDatabasesKeepChanging) {
  // A loaded database is one segment per 65,536 ids; adds make new ones
  // after it, and removals compact it.
  const Vocabulary vocabulary = wide_vocabulary(10, 4, Scoring::kChiSquare);
  std::mt19937_64 rng(21);
  std::vector<BowVector> bows;
  for (int i = 0; i < 900; ++i) bows.push_back(random_bow(200, vocabulary.word_count(), rng));
  std::vector<bool> live(bows.size(), false);
  Database first(vocabulary, {false, 0});
  for (std::size_t i = 0; i < 300; ++i) {
    first.add(bows[i]);
    live[i] = true;
  }
  const std::vector<std::uint8_t> bytes = first.serialize(false);
  Database database = Database::deserialize(bytes.data(), bytes.size(), "memory", vocabulary);
  for (std::size_t i = 300; i < bows.size(); ++i) {
    database.add(bows[i]);
    live[i] = true;
  }
  for (EntryId id = 0; id < 600; id += 3) {
    database.remove(id);
    live[id] = false;
  }
  for (EntryId id = 1; id < 300; id += 3) {
    database.remove(id);
    live[id] = false;
  }
  const std::vector<std::uint8_t> again = database.serialize(false);
  const Database reloaded = Database::deserialize(again.data(), again.size(), "memory", vocabulary);
  for (int q = 0; q < 6; ++q) {
    const BowVector& query = bows[rng() % bows.size()];
    for (EntryId max_id : {kAllEntries, EntryId{250}, EntryId{450}}) {
      const auto expected = brute_force(vocabulary, bows, live, query, 20, max_id);
      expect_same_results(database.query(query, 20, max_id), expected, "loaded, then changed");
      expect_same_results(reloaded.query(query, 20, max_id), expected, "saved again and loaded");
    }
  }
}

TEST(Database, IdsAreDenseAndClearRestarts) {
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  const Corpus corpus = random_corpus(vocabulary, 10, 2);
  Database database(vocabulary);
  for (EntryId i = 0; i < 10; ++i) EXPECT_EQ(database.add(corpus.images[i].view()), i);
  EXPECT_EQ(database.size(), 10u);
  EXPECT_EQ(database.next_entry_id(), 10u);
  database.remove(3);
  EXPECT_EQ(database.size(), 9u);
  EXPECT_EQ(database.next_entry_id(), 10u);
  database.clear();
  EXPECT_EQ(database.size(), 0u);
  EXPECT_TRUE(database.query(corpus.bows[0], 10).empty());
  EXPECT_EQ(database.add(corpus.bows[0]), 0u);
  EXPECT_EQ(database.query(corpus.bows[0], 10).at(0).entry, 0u);
}

TEST(Database, DirectIndexMatchesTransform) {
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  const Corpus corpus = random_corpus(vocabulary, 20, 4);
  for (unsigned levels_up : {0u, 1u, 2u, 9u}) {
    Database database(vocabulary, {true, levels_up});
    for (const auto& image : corpus.images) database.add(image.view());
    for (EntryId i = 0; i < corpus.images.size(); ++i) {
      BowVector bow;
      FeatureVector expected;
      vocabulary.transform(corpus.images[i].view(), bow, expected, levels_up);
      EXPECT_EQ(database.feature_vector(i), expected) << "levels_up " << levels_up;
      EXPECT_EQ(database.query(bow, 1).at(0).entry, i);
    }
  }
}

TEST(Database, DirectIndexWithLargeFeatureIndices) {
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  Database database(vocabulary);
  const FeatureVector features =
      FeatureVector::from_arrays({1, 2, 5}, {0, 2, 3, 5}, {7, 70000, 12, 3, 100000});
  const EntryId id = database.add(BowVector({{0, 0.5f}, {3, 0.5f}}), features);
  EXPECT_EQ(database.feature_vector(id), features);
  // Every feature under exactly one of 300 nodes (16-bit node positions).
  std::vector<NodeId> many_nodes;
  std::vector<std::uint32_t> many_offsets{0}, many_features;
  for (std::uint32_t n = 0; n < 300; ++n) {
    many_nodes.push_back(n + 100);
    many_features.push_back(299 - n);
    many_offsets.push_back(n + 1);
  }
  const FeatureVector many = FeatureVector::from_arrays(many_nodes, many_offsets, many_features);
  VocabularyTree tree;  // k=20, L=2: 421 nodes
  tree.code_size = 32;
  tree.branching = 20;
  tree.levels = 2;
  tree.parent.push_back(0);
  for (NodeId n = 0; n < 20; ++n) tree.parent.push_back(0);
  for (NodeId n = 0; n < 400; ++n) tree.parent.push_back(1 + n / 20);
  tree.descriptors.resize(tree.parent.size() * 32);
  for (std::size_t i = 0; i < tree.descriptors.size(); ++i)
    tree.descriptors[i] = static_cast<std::uint8_t>(i * 37 + i / 32);
  tree.weights.assign(tree.parent.size(), 1.0f);
  Database wide_database(Vocabulary::from_tree(tree));
  EXPECT_EQ(wide_database.feature_vector(wide_database.add(BowVector({{2, 1.0f}}), many)), many);
  // A node holding several features, features unordered across nodes.
  const FeatureVector mixed = FeatureVector::from_arrays({3, 9}, {0, 3, 5}, {1, 3, 4, 0, 2});
  EXPECT_EQ(database.feature_vector(database.add(BowVector({{2, 1.0f}}), mixed)), mixed);
  const FeatureVector small = FeatureVector::from_arrays({4}, {0, 2}, {1, 2});
  EXPECT_EQ(database.feature_vector(database.add(BowVector({{1, 1.0f}}), small)), small);
  EXPECT_EQ(database.feature_vector(database.add(BowVector({{1, 1.0f}}))), FeatureVector());
  // Node ids are packed as steps in 8, 16 or 32 bits, as the largest needs.
  Database by_word_ids = Database::over_word_ids(Scoring::kL1);
  for (const std::vector<NodeId>& nodes : std::vector<std::vector<NodeId>>{{0, 255},
                                                                           {7, 263},
                                                                           {300, 555},
                                                                           {1, 65535},
                                                                           {70000, 135535},
                                                                           {255, 65792},
                                                                           {65536, 4000000000u}}) {
    const FeatureVector packed = FeatureVector::from_arrays(nodes, {0, 1, 3}, {2, 0, 1});
    EXPECT_EQ(by_word_ids.feature_vector(by_word_ids.add(BowVector({{1, 1.0f}}), packed)), packed)
        << "largest node " << nodes.back();
  }
}

TEST(Database, WithoutDirectIndex) {
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  Database database(vocabulary, {false, 0});
  const EntryId id = database.add(BowVector({{0, 1.0f}}));
  EXPECT_THROW(database.feature_vector(id), InvalidArgument);
}

TEST(Database, BadInput) {
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  EXPECT_THROW(Database{Vocabulary{}}, InvalidArgument);
  // A level a .bbdb file cannot record: such a database could be saved, never loaded.
  EXPECT_THROW(Database(vocabulary, {true, kMaxDirectIndexLevelsUp + 1}), InvalidArgument);
  EXPECT_NO_THROW(Database(vocabulary, {true, kMaxDirectIndexLevelsUp}));
  Database database(vocabulary);
  const Corpus corpus = random_corpus(vocabulary, 5, 8);
  for (const auto& bow : corpus.bows) database.add(bow);

  EXPECT_TRUE(database.query(BowVector(), 10).empty());
  EXPECT_TRUE(database.query(corpus.bows[0], 0).empty());
  const auto word_count = static_cast<WordId>(vocabulary.word_count());
  EXPECT_THROW(database.query(BowVector({{word_count, 1.0f}}), 5), InvalidArgument);
  EXPECT_THROW(database.add(BowVector({{word_count, 1.0f}})), InvalidArgument);
  EXPECT_THROW(database.add(BowVector({{0, std::nanf("")}})), InvalidArgument);
  {
    // Found after some words went in: the database is left as it was.
    const EntryId next = database.next_entry_id();
    const std::size_t size = database.size();
    const auto before = database.query(BowVector({{0, 0.5f}, {1, 0.5f}, {2, 0.5f}}), 100);
    EXPECT_THROW(database.add(BowVector({{0, 0.5f}, {1, 0.5f}, {2, INFINITY}})), InvalidArgument);
    EXPECT_EQ(database.next_entry_id(), next);
    EXPECT_EQ(database.size(), size);
    const auto after = database.query(BowVector({{0, 0.5f}, {1, 0.5f}, {2, 0.5f}}), 100);
    ASSERT_EQ(after.size(), before.size());
    for (std::size_t i = 0; i < after.size(); ++i) {
      EXPECT_EQ(after[i].entry, before[i].entry);
      EXPECT_EQ(after[i].score, before[i].score);
    }
  }
  EXPECT_THROW(database.query(BowVector({{0, INFINITY}}), 5), InvalidArgument);
  const auto node_count = static_cast<NodeId>(vocabulary.node_count());
  EXPECT_THROW(
      database.add(BowVector({{0, 1.0f}}), FeatureVector::from_arrays({node_count}, {0, 1}, {0})),
      InvalidArgument);
  EXPECT_EQ(database.next_entry_id(), 5u) << "failed adds must not consume ids";

  std::mt19937_64 rng(1);
  const DescriptorMatrix wrong = test::random_descriptors(10, 16, rng);
  EXPECT_THROW(database.add(wrong.view()), InvalidArgument);

  EXPECT_THROW(database.remove(5), InvalidArgument);
  EXPECT_THROW(database.remove(kAllEntries), InvalidArgument);
  EXPECT_THROW(database.feature_vector(99), InvalidArgument);
  EXPECT_THROW(database.label(99), InvalidArgument);
  EXPECT_THROW(database.set_label(99, "x"), InvalidArgument);
  EXPECT_FALSE(database.contains(99));
  // An empty image is a valid entry that no query finds.
  const EntryId empty = database.add(BowVector());
  EXPECT_TRUE(database.contains(empty));
  for (const auto& r : database.query(corpus.bows[0], 100)) EXPECT_NE(r.entry, empty);
}

TEST(Database, NegativeValuesGiveAWellDefinedOrder) {
  // KL of negative values is NaN: such entries rank last instead of breaking the sort.
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf).with_scoring(Scoring::kKL);
  Database database(vocabulary);
  for (int i = 0; i < 50; ++i)
    database.add(BowVector({{0, i % 2 ? -0.5f : 0.5f}, {1, 0.25f * static_cast<float>(i % 3)}}));
  const auto results = database.query(BowVector({{0, 0.5f}, {1, 0.5f}}), 100);
  EXPECT_EQ(results.size(), 50u);
}

// A float in [2^lowest_exponent, 1): its exponent uniform, its significand random.
float random_magnitude(int lowest_exponent, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> exponent(lowest_exponent, -1);
  std::uniform_real_distribution<float> significand(1.0f, 2.0f);
  return std::ldexp(significand(rng), exponent(rng));
}

TEST(Database, L1TermsAreMinimumsWithinTheirRange) {
  // The identity the L1 query kernel relies on (core/scoring.h): DBoW2's term
  // is exactly -2 min(v, w) for every pair the check admits, and is not for
  // some pairs further apart, so the check is needed.
  std::mt19937_64 rng(3);
  std::size_t admitted = 0;
  std::size_t refused_and_different = 0;
  for (int i = 0; i < 1'000'000; ++i) {
    const float v = random_magnitude(-60, rng);
    const float w = random_magnitude(-60, rng);
    detail::ValueRange index_values;
    detail::ValueRange query_values;
    index_values.include(w);
    query_values.include(v);
    const double term = detail::score_term(Scoring::kL1, v, w);
    const double minimums = -2.0 * static_cast<double>(std::min(v, w));
    if (detail::l1_terms_are_minimums(index_values, query_values)) {
      ++admitted;
      ASSERT_EQ(bits_of(term), bits_of(minimums)) << v << ", " << w;
    } else {
      refused_and_different += term != minimums;
    }
  }
  EXPECT_GT(admitted, 400'000u);
  EXPECT_GT(refused_and_different, 1000u);
  EXPECT_EQ(
      bits_of(detail::l1_score_of_minimums(0.0)),
      bits_of(detail::finish_score(Scoring::kL1, detail::score_term(Scoring::kL1, 0.5, 0.0), 0.0)));
}

TEST(Database, L1ScoresAreExactWhateverTheValuesSpan) {
  // Queries sum L1 terms as minimums when every value is non-negative and
  // within a ratio of 2^29 of the others; otherwise (negative values, values
  // further apart) they sum DBoW2's terms. Both give the brute force's scores
  // to the last bit, zeros included.
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  ASSERT_EQ(vocabulary.scoring(), Scoring::kL1);
  struct Case {
    const char* name;
    int lowest_exponent;
    bool negatives;
    bool minimums;  // what the values admit
  };
  for (const Case c :
       {Case{"within 2^29", -28, false, true}, Case{"further apart", -60, false, false},
        Case{"negative", -8, true, false}}) {
    std::mt19937_64 rng(11);
    std::bernoulli_distribution coin(0.2);
    const auto random_values = [&](std::size_t words) {
      std::vector<BowEntry> entries;
      for (WordId word = 0; word < vocabulary.word_count(); ++word) {
        if (rng() % vocabulary.word_count() >= words) continue;
        float value = coin(rng) ? 0.0f : random_magnitude(c.lowest_exponent, rng);
        if (c.negatives && coin(rng)) value = -value;
        entries.push_back({word, value});
      }
      return BowVector(std::move(entries));
    };
    Database database(vocabulary, {false, 0});
    std::vector<BowVector> bows;
    detail::ValueRange values;
    for (int i = 0; i < 400; ++i) {
      bows.push_back(random_values(20));
      for (const BowEntry& e : bows.back()) values.include(e.value);
      database.add(bows.back());
    }
    // An entry that shares only a zero with the query scores -0.0.
    bows.push_back(BowVector({{0, 0.0f}}));
    database.add(bows.back());
    const std::vector<bool> live(bows.size(), true);
    for (int q = 0; q < 40; ++q) {
      BowVector query = random_values(30);
      if (q == 0) query = BowVector({{0, 0.5f}});
      ASSERT_EQ(detail::l1_terms_are_minimums(values, detail::value_range(query)), c.minimums)
          << c.name;
      expect_same_results(database.query(query, 1000),
                          brute_force(vocabulary, bows, live, query, 1000), c.name);
    }
    const auto zero = database.query(BowVector({{0, 0.5f}}), 1000);
    ASSERT_FALSE(zero.empty());
    EXPECT_EQ(bits_of(zero.back().score), bits_of(-0.0)) << c.name;
  }
}

TEST(Database, EveryEntryTouchedByManyWords) {
  // Every entry shares every query word: the touched list fills up completely.
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  Database database(vocabulary);
  std::vector<BowEntry> entries;
  for (WordId w = 0; w < 20; ++w) entries.push_back({w, 0.05f});
  const BowVector bow(entries);
  for (int i = 0; i < 3; ++i) database.add(bow);
  const auto results = database.query(bow, 10);
  ASSERT_EQ(results.size(), 3u);
  for (EntryId i = 0; i < 3; ++i) {
    EXPECT_EQ(results[i].entry, i);
    EXPECT_EQ(results[i].shared_words, 20u);
  }
}

TEST(Database, Labels) {
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  Database database(vocabulary);
  const EntryId a = database.add(BowVector({{0, 1.0f}}));
  EXPECT_EQ(database.label(a), "");
  database.set_label(a, "images/a.png");
  const EntryId b = database.add(BowVector({{1, 1.0f}}));
  EXPECT_EQ(database.label(a), "images/a.png");
  EXPECT_EQ(database.label(b), "");

  // Labelled as it is added: another thread cannot remove the entry between
  // the two steps and make the label fail after the add succeeded.
  const EntryId c = database.add(BowVector({{2, 1.0f}}), {}, "images/c.png");
  EXPECT_EQ(database.label(c), "images/c.png");
  const Corpus corpus = random_corpus(vocabulary, 1, 6);
  const EntryId d = database.add(corpus.images[0].view(), "images/d.png");
  EXPECT_EQ(database.label(d), "images/d.png");
  Database online = Database::over_word_ids(Scoring::kL1);
  const EntryId e = online.add(BowVector({{70000, 1.0f}}), {}, "frame 0");
  EXPECT_EQ(online.label(e), "frame 0");
}

TEST(Database, MemoryUsageGrowsWithEntries) {
  const Vocabulary vocabulary = small_vocabulary(Weighting::kTfIdf);
  const Corpus corpus = random_corpus(vocabulary, 50, 6);
  Database database(vocabulary);
  const std::size_t empty = database.memory_usage();
  for (const auto& image : corpus.images) database.add(image.view());
  EXPECT_GT(database.memory_usage(), empty);
}

}  // namespace
}  // namespace binbow

namespace binbow {
namespace {

// 1000 features under 100 nodes in 10 runs of 10 siblings (a direct index 4
// levels up a k=10 L=6 tree): node positions take 7 bits, node ids a few
// bytes per run; the packed vector gives back the same FeatureVector.
TEST(PackedFeatureVector, SevenBitPositionsAndRunsOfSiblings) {
  std::vector<NodeId> assignment;
  std::mt19937_64 rng(4);
  for (int f = 0; f < 1000; ++f) {
    const auto node = static_cast<NodeId>(f % 100);
    assignment.push_back(11 + (node / 10) * 11111 + node % 10);
  }
  std::shuffle(assignment.begin(), assignment.end(), rng);
  const FeatureVector features =
      FeatureVector::from_assignment(assignment.data(), assignment.size());
  ASSERT_EQ(features.size(), 100u);
  const detail::PackedFeatureVector packed(features);
  EXPECT_EQ(packed.unpack(), features);
  EXPECT_LE(packed.memory_usage(), 875u + 10 * 4);
  // Decoding its stored form gives the same vector; a cut form is refused.
  std::vector<std::uint8_t> stored(packed.encoded_size());
  packed.encode(stored.data());
  EXPECT_EQ(detail::PackedFeatureVector::decode(stored.data(), stored.size(), 100, 1000, 1u << 20)
                .unpack(),
            features);
  EXPECT_THROW(
      detail::PackedFeatureVector::decode(stored.data(), stored.size() - 1, 100, 1000, 1u << 20),
      InvalidArgument);
}

}  // namespace
}  // namespace binbow
