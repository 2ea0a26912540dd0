// Segment rows of entries made by Vocabulary::transform hold word counts,
// their weights computed again from the entry's divisor. With more than
// 65,536 words a row group holds several words (w and w + 65,536) and a
// tail list several groups: transform-made entries (some with a word
// counted more often than a count row holds, some entries not made by
// transform at all) go through the tail's list-by-list freezes, a merge of
// the segments and compactions, and every query, exact and fast, is checked
// against brute force (Vocabulary::score), then again after a save and a
// load of the file, whose count rows and divisors are checked too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/vocabulary.h"
#include "support/query_results.h"
#include "support/random_tree.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::bbdb_section;
using test::bits_of;
using test::expect_same_results;

// The .bbdb sections read here (docs/database-files.md), by their index in
// the section table.
constexpr std::uint32_t kRowsSection = 4;
constexpr std::uint32_t kPostingsSection = 5;
constexpr std::uint32_t kDivisorsSection = 6;
constexpr std::uint8_t kCountRowFlag = 16;
constexpr std::uint32_t kMaxRowCount = 255;

std::uint32_t shared_words(const BowVector& a, const BowVector& b) {
  std::uint32_t shared = 0;
  for (auto i = a.begin(), j = b.begin(); i != a.end() && j != b.end();) {
    if (i->word == j->word) ++shared;
    const WordId word = i->word;
    if (word <= j->word) ++i;
    if (j->word <= word) ++j;
  }
  return shared;
}

bool better(Scoring scoring, const QueryResult& a, const QueryResult& b) {
  if (a.score != b.score) return scoring == Scoring::kKL ? a.score < b.score : a.score > b.score;
  return a.entry < b.entry;
}

// Every live entry that shares a word with the query, scored by the
// vocabulary, best first, ties by id.
std::vector<QueryResult> brute_force(const Vocabulary& vocabulary,
                                     const std::vector<BowVector>& bows,
                                     const std::vector<bool>& live, const BowVector& query) {
  std::vector<QueryResult> all;
  for (EntryId id = 0; id < bows.size(); ++id) {
    if (!live[id]) continue;
    const std::uint32_t shared = shared_words(query, bows[id]);
    if (shared != 0) all.push_back({id, vocabulary.score(query, bows[id]), shared});
  }
  std::sort(all.begin(), all.end(), [&](const QueryResult& a, const QueryResult& b) {
    return better(vocabulary.scoring(), a, b);
  });
  return all;
}

// The first max_results of `all` up to max_entry_id.
std::vector<QueryResult> best(const std::vector<QueryResult>& all, std::size_t max_results,
                              EntryId max_entry_id) {
  std::vector<QueryResult> out;
  for (const QueryResult& r : all)
    if (r.entry <= max_entry_id && out.size() < max_results) out.push_back(r);
  return out;
}

// Fast queries may miss entries, never misscore or misrank one: each
// result is a live entry with brute force's score, in a query's order, and
// the query's own entry (unique, and the best under L1 and L2) comes first.
void expect_fast(const std::vector<QueryResult>& results, const Vocabulary& vocabulary,
                 const std::vector<BowVector>& bows, const std::vector<bool>& live,
                 const BowVector& query, EntryId self, EntryId max_entry_id,
                 const std::string& context, bool self_first = true) {
  ASSERT_FALSE(results.empty()) << context;
  for (std::size_t i = 0; i < results.size(); ++i) {
    const QueryResult& r = results[i];
    ASSERT_LT(r.entry, bows.size()) << context;
    EXPECT_TRUE(live[r.entry]) << context << ": entry " << r.entry << " was removed";
    EXPECT_LE(r.entry, max_entry_id) << context;
    EXPECT_EQ(bits_of(r.score), bits_of(vocabulary.score(query, bows[r.entry])))
        << context << " entry " << r.entry;
    EXPECT_EQ(r.shared_words, shared_words(query, bows[r.entry])) << context;
    if (i > 0) {
      EXPECT_TRUE(better(vocabulary.scoring(), results[i - 1], r)) << context << " rank " << i;
    }
  }
  const Scoring scoring = vocabulary.scoring();
  if (self_first && self <= max_entry_id && (scoring == Scoring::kL1 || scoring == Scoring::kL2)) {
    EXPECT_EQ(results[0].entry, self) << context;
  }
}

// 5^7 = 78,125 words: words w and w + 65,536 share a row group for w below
// 12,589. A complete tree descends in 35 distances per descriptor.
Vocabulary wide_vocabulary(Scoring scoring) {
  const Vocabulary vocabulary = Vocabulary::from_tree(test::complete_random_tree(5, 7, 32, 21));
  return vocabulary.with_scoring(scoring);
}

// Images as descriptors of a pool whose words are known: common ones on
// both sides of the group boundary (in half the images, counted once or
// twice), rare ones, and now and then one descriptor 255 times (the largest
// count a count row holds) or 300 times (an entry of weights, not counts).
struct Corpus {
  DescriptorMatrix pool{32};
  std::vector<WordId> pool_words;
  std::vector<std::vector<std::uint32_t>> images;  // pool rows
  std::vector<bool> counted;                       // every word counted at most kMaxRowCount times

  Corpus(const Vocabulary& vocabulary, std::size_t count, std::mt19937_64& rng) {
    pool = test::random_descriptors(20'000, 32, rng);
    std::map<WordId, std::uint32_t> row_of_word;
    for (std::uint32_t row = 0; row < pool.rows(); ++row) {
      BowVector bow;
      vocabulary.transform(pool.view().slice(row, 1), bow);
      pool_words.push_back(bow[0].word);
      row_of_word.emplace(bow[0].word, row);
    }
    std::vector<std::uint32_t> common;
    for (const auto& [word, row] : row_of_word) {
      const auto partner = row_of_word.find(word - 65'536);
      if (word >= 65'536 && partner != row_of_word.end() && common.size() < 40) {
        common.push_back(row);
        common.push_back(partner->second);
      }
    }
    if (common.size() < 40) throw std::runtime_error("too few common words on both sides");
    for (std::uint32_t row = 0; common.size() < 60; row += 97) common.push_back(row);
    std::uniform_int_distribution<std::uint32_t> rare(0,
                                                      static_cast<std::uint32_t>(pool.rows()) - 1);
    for (std::size_t i = 0; i < count; ++i) {
      std::vector<std::uint32_t> image;
      for (std::uint32_t row : common)
        if (rng() % 2 == 0) image.insert(image.end(), 1 + rng() % 2, row);
      for (std::size_t j = 120 + rng() % 120; j-- > 0;) image.push_back(rare(rng));
      if (i % 53 == 5) image.insert(image.end(), kMaxRowCount, rare(rng));
      if (i % 59 == 8) image.insert(image.end(), 300, rare(rng));
      std::shuffle(image.begin(), image.end(), rng);
      std::map<WordId, std::uint32_t> counts;
      std::uint32_t largest = 0;
      for (std::uint32_t row : image) largest = std::max(largest, ++counts[pool_words[row]]);
      counted.push_back(largest <= kMaxRowCount);
      images.push_back(std::move(image));
    }
  }

  BowVector transform(const Vocabulary& vocabulary, std::size_t image) const {
    const std::vector<std::uint32_t>& rows = images[image];
    DescriptorMatrix descriptors(rows.size(), 32);
    for (std::size_t i = 0; i < rows.size(); ++i)
      std::memcpy(descriptors.row(i), pool.row(rows[i]), 32);
    BowVector bow;
    vocabulary.transform(descriptors.view(), bow);
    return bow;
  }
};

// Fast queries that search candidates in these small databases, rather
// than reading every posting.
const QueryOptions kFewCandidates = [] {
  QueryOptions options{QueryMode::kFast, 1};
  options.fast_candidates = 20;
  options.fast_candidate_share = 0;
  options.fast_min_postings = 1 << 10;
  return options;
}();

// Every value times 2^-100: a query whose divisor, taken from its values,
// is not its entries' (and 2^-130 for one, below the normal floats).
BowVector scaled_down(const BowVector& bow) {
  std::vector<BowEntry> entries(bow.begin(), bow.end());
  for (BowEntry& e : entries) e.value = std::ldexp(e.value, -100);
  entries.front().value = std::ldexp(bow.begin()->value, -130);
  return BowVector(std::move(entries));
}

// A weight one ulp off: not what transform gives, so kept as weights.
BowVector nudged(const BowVector& bow) {
  std::vector<BowEntry> entries(bow.begin(), bow.end());
  entries[entries.size() / 2].value = std::nextafter(entries[entries.size() / 2].value, 1.0f);
  return BowVector(std::move(entries));
}

// The count rows of words beyond 65,535 in a saved file: the rows section
// lists (word, bytes) per row, the postings section starts each row with
// its header byte.
std::size_t count_rows_beyond_65535(const std::vector<std::uint8_t>& file) {
  const auto [rows, rows_length] = bbdb_section(file, kRowsSection);
  const auto [postings, postings_length] = bbdb_section(file, kPostingsSection);
  std::size_t found = 0, position = 0;
  for (std::size_t r = 0; r + 8 <= rows_length; r += 8) {
    std::uint32_t word = 0, bytes = 0;
    std::memcpy(&word, file.data() + rows + r, 4);
    std::memcpy(&bytes, file.data() + rows + r + 4, 4);
    if (position >= postings_length) return 0;
    if (word >= 65'536 && (file[postings + position] & kCountRowFlag) != 0) ++found;
    position += bytes;
  }
  return position == postings_length ? found : 0;
}

TEST(DatabaseCountRows, TransformMadeEntriesOfAVocabularyOfMoreThan65536Words) {
  // 156,250 postings freeze the tail (twice the words); ~205 words per
  // image: a segment every ~750 images, the first eight merge at ~6,000.
  constexpr std::size_t kImages = 6'300;
  std::mt19937_64 rng(31);
  const Corpus corpus(wide_vocabulary(Scoring::kL1), kImages, rng);
  std::vector<BowVector> l1_bows;  // transform's, the same under KL (both L1-normalise)
  for (Scoring scoring : {Scoring::kL1, Scoring::kKL, Scoring::kL2, Scoring::kDotProduct}) {
    const std::string name = to_string(scoring);
    const Vocabulary vocabulary = wide_vocabulary(scoring);
    ASSERT_EQ(vocabulary.word_count(), 78'125u);
    std::vector<BowVector> bows;
    std::vector<bool> live, counts;  // counts: stored as counts, with a divisor
    Database database(vocabulary, {false, 0});
    const auto check = [&](const Database& db, const std::string& context) {
      for (int q = 0; q < 2; ++q) {
        EntryId self = static_cast<EntryId>(rng() % bows.size());
        while (!live[self]) self = static_cast<EntryId>(rng() % bows.size());
        const std::vector<QueryResult> all = brute_force(vocabulary, bows, live, bows[self]);
        for (EntryId max_id : {kAllEntries, static_cast<EntryId>(rng() % bows.size())}) {
          const std::string where = name + " " + context + " query " + std::to_string(self);
          expect_same_results(db.query(bows[self], 12, max_id), best(all, 12, max_id), where);
          expect_fast(db.query(bows[self], 12, max_id, {QueryMode::kFast, 1}), vocabulary, bows,
                      live, bows[self], self, max_id, where + " fast");
          // Candidates from the count rows' rare words, whose weights take
          // the query's divisor for the entries'; and from a query scaled
          // down, not made by transform: its divisor is not the entries'.
          expect_fast(db.query(bows[self], 12, max_id, kFewCandidates), vocabulary, bows, live,
                      bows[self], self, max_id, where + " fast, 20 candidates");
          const BowVector scaled = scaled_down(bows[self]);
          expect_fast(db.query(scaled, 12, max_id, kFewCandidates), vocabulary, bows, live, scaled,
                      self, max_id, where + " fast, 20 candidates, scaled query", false);
        }
      }
    };
    for (std::size_t i = 0; i < kImages; ++i) {
      const bool reused = scoring == Scoring::kKL;
      BowVector bow = reused ? l1_bows[i] : corpus.transform(vocabulary, i);
      if (reused && i % 700 == 0) {
        ASSERT_TRUE(bow == corpus.transform(vocabulary, i)) << "image " << i;
      }
      if (scoring == Scoring::kL1) l1_bows.push_back(bow);
      const bool weights = i % 29 == 3;
      if (weights) bow = nudged(bow);
      ASSERT_EQ(database.add(bow), static_cast<EntryId>(i));
      bows.push_back(std::move(bow));
      live.push_back(true);
      counts.push_back(corpus.counted[i] && !weights);
      if (i == 999 || i == 3'499 || i + 1 == kImages)
        check(database, "after " + std::to_string(i + 1) + " images");
    }
    // Thin out the merged segment until it is compacted, and the tail.
    for (EntryId id = 0; id < kImages; id += 1 + id % 3) {
      database.remove(id);
      live[id] = false;
    }
    check(database, "after removals");
    ASSERT_GT(std::count(counts.begin(), counts.end(), false), 100);

    test::TempDir dir;
    const std::string path = dir.file("db.bbdb");
    database.save(path, false);
    const std::vector<std::uint8_t> file = test::read_file(path);
    const auto [divisors, divisors_length] = bbdb_section(file, kDivisorsSection);
    ASSERT_EQ(divisors_length, 8 * kImages) << name;
    for (EntryId id = 0; id < kImages; ++id) {
      double divisor = 0;
      std::memcpy(&divisor, file.data() + divisors + 8 * std::size_t{id}, 8);
      EXPECT_EQ(divisor > 0, live[id] && counts[id]) << name << " entry " << id;
    }
    EXPECT_GT(count_rows_beyond_65535(file), 100u) << name;
    for (Verification verification : {Verification::kBackground, Verification::kBeforeReturn}) {
      const Database loaded = Database::load(path, vocabulary, {verification});
      check(loaded, "loaded");
      loaded.wait_until_verified();
      EXPECT_EQ(loaded.serialize(false), database.serialize(false)) << name;
    }
  }
}

}  // namespace
}  // namespace binbow
