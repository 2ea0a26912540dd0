// The forward index that fast queries score their candidates from gives
// back every entry's words and weights bit for bit, in about 2 bytes per word
// for vectors made by Vocabulary::transform.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/vocabulary.h"
#include "core/count_form.h"
#include "core/forward_index.h"
#include "support/test_support.h"

namespace binbow {
namespace {

Vocabulary trained_vocabulary(Weighting weighting) {
  std::mt19937_64 rng(5);
  std::vector<DescriptorMatrix> images;
  for (int i = 0; i < 30; ++i)
    images.push_back(test::clustered_descriptors(300, 32, 200, 0.08, rng));
  std::vector<DescriptorView> views;
  for (const auto& image : images) views.push_back(image.view());
  BuildOptions options;
  options.branching = 8;
  options.levels = 4;
  options.weighting = weighting;
  options.seed = 2;
  options.threads = 1;
  return Vocabulary::build(views, options);
}

std::uint32_t bits_of(float value) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}

// What for_each_shared gives for a query that holds every word id below
// `words`: the entry's (word, weight) in order.
std::vector<BowEntry> read_back(const detail::ForwardIndex& index, EntryId entry,
                                std::size_t words) {
  std::vector<double> weights(words);
  for (WordId w = 0; w < words; ++w) weights[w] = index.word_weight(w);
  std::vector<std::uint32_t> hits;
  std::vector<BowEntry> result;
  index.for_each_shared(
      entry, [](WordId word) { return word; }, static_cast<std::uint32_t>(words), weights.data(),
      hits,
      [&](std::uint32_t q, float weight) {
        result.push_back({q, weight});
      });
  return result;
}

void expect_same(const std::vector<BowEntry>& actual, const BowVector& expected,
                 const std::string& context) {
  ASSERT_EQ(actual.size(), expected.size()) << context;
  for (std::size_t i = 0; i < actual.size(); ++i) {
    EXPECT_EQ(actual[i].word, expected[i].word) << context << " word " << i;
    EXPECT_EQ(bits_of(actual[i].value), bits_of(expected[i].value)) << context << " word " << i;
  }
}

TEST(ForwardIndex, TransformedVectorsAreKeptExactlyInTwoBytesPerWord) {
  for (Weighting weighting :
       {Weighting::kTfIdf, Weighting::kTf, Weighting::kIdf, Weighting::kBinary}) {
    const Vocabulary trained = trained_vocabulary(weighting);
    ASSERT_GT(trained.word_count(), 1000u);
    for (Scoring scoring : {Scoring::kL1, Scoring::kL2, Scoring::kChiSquare, Scoring::kKL,
                            Scoring::kBhattacharyya, Scoring::kDotProduct}) {
      const Vocabulary vocabulary = trained.with_scoring(scoring);
      const std::string context =
          std::string(to_string(weighting)) + " " + std::string(to_string(scoring));
      detail::ForwardIndex index(&vocabulary, scoring);
      std::mt19937_64 rng(9);
      std::vector<BowVector> bows;
      std::size_t words = 0;
      for (int i = 0; i < 40; ++i) {
        // Many features per word: counts above 1.
        const DescriptorMatrix image =
            test::clustered_descriptors(100 + 40 * i, 32, 200, 0.08, rng);
        BowVector bow;
        vocabulary.transform(image.view(), bow);
        words += bow.size();
        index.append(Span<BowEntry>(bow.begin(), bow.size()));
        bows.push_back(std::move(bow));
      }
      for (EntryId e = 0; e < bows.size(); ++e)
        expect_same(read_back(index, e, vocabulary.word_count()), bows[e],
                    context + " entry " + std::to_string(e));
      const double bytes_per_word =
          static_cast<double>(index.memory_usage()) / static_cast<double>(words);
      EXPECT_LT(bytes_per_word, 2.6) << context;
    }
  }
}

TEST(ForwardIndex, OtherVectorsKeepTheirFloats) {
  // Weights that no vocabulary gives, words far apart (steps beyond 15
  // bits), over word ids and with a vocabulary.
  const Vocabulary vocabulary = trained_vocabulary(Weighting::kTfIdf);
  const std::vector<BowVector> bows = {
      BowVector({{0, 0.25f}, {1, 0.5f}, {70'000, -1.5f}, {4'000'000'000u, 3e-30f}}),
      BowVector({{5, 1.0f}}),
      BowVector(),
      BowVector({{32'767, 0.125f}, {65'535, 0.75f}, {65'536, 0.0f}}),
  };
  for (const bool over_word_ids : {true, false}) {
    detail::ForwardIndex index(over_word_ids ? nullptr : &vocabulary, Scoring::kL1);
    for (const BowVector& bow : bows) index.append(Span<BowEntry>(bow.begin(), bow.size()));
    index.append(Span<BowEntry>(bows[1].begin(), bows[1].size()));
    for (EntryId e = 0; e < bows.size(); ++e) {
      std::vector<BowEntry> all;
      std::vector<std::uint32_t> hits;
      // Position: the word's index in the entry itself, so that any word id works.
      const BowVector& bow = bows[e];
      std::vector<double> weights;
      for (const BowEntry& word : bow) weights.push_back(index.word_weight(word.word));
      index.for_each_shared(
          e,
          [&](WordId word) {
            for (std::uint32_t i = 0; i < bow.size(); ++i)
              if (bow[i].word == word) return i;
            return static_cast<std::uint32_t>(bow.size());
          },
          static_cast<std::uint32_t>(bow.size()), weights.data(), hits,
          [&](std::uint32_t q, float weight) {
            all.push_back({bow[q].word, weight});
          });
      expect_same(all, bow, "entry " + std::to_string(e));
    }
    index.drop(1);
    std::vector<std::uint32_t> hits;
    int calls = 0;
    index.for_each_shared(
        1, [](WordId) { return 0u; }, 1, nullptr, hits, [&](std::uint32_t, float) { ++calls; });
    EXPECT_EQ(calls, 0) << "a dropped entry has no words";
    index.truncate(2);
    EXPECT_EQ(index.size(), 2u);
  }
}

// Transformed images of `vocabulary`, one of them with a word counted 300
// times (beyond a segment row's counts, within the forward index's), and
// one vector no transform gives.
std::vector<BowVector> mixed_vectors(const Vocabulary& vocabulary, std::size_t images,
                                     std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<BowVector> bows;
  for (std::size_t i = 0; i < images; ++i) {
    DescriptorMatrix image = test::clustered_descriptors(100 + 7 * (i % 30), 32, 200, 0.08, rng);
    if (i % 480 == 29)  // 303 descriptors
      for (std::size_t row = 1; row < 300; ++row)
        std::memcpy(image.row(row), image.row(0), image.code_size());
    BowVector bow;
    vocabulary.transform(image.view(), bow);
    bows.push_back(std::move(bow));
  }
  bows[5] = BowVector({{0, 0.25f}, {7, 0.5f}, {100, 1.5f}});
  return bows;
}

TEST(ForwardIndex, AppendingTheAddsCountFormKeepsTheSameEntries) {
  const Vocabulary vocabulary = trained_vocabulary(Weighting::kTfIdf);
  const std::vector<BowVector> bows = mixed_vectors(vocabulary, 30, 4);
  detail::ForwardIndex found_again(&vocabulary, Scoring::kL1);
  detail::ForwardIndex given(&vocabulary, Scoring::kL1);
  detail::CountForm form;
  std::size_t counted = 0;
  for (const BowVector& bow : bows) {
    const Span<BowEntry> words(bow.begin(), bow.size());
    found_again.append(words);
    const bool found = form.find(vocabulary, Scoring::kL1, words);
    counted += found ? 1 : 0;
    given.append(words, found ? &form : nullptr);
  }
  EXPECT_EQ(counted, bows.size() - 1) << "only the vector no transform gives has floats";
  EXPECT_EQ(given.memory_usage(), found_again.memory_usage());
  for (EntryId e = 0; e < bows.size(); ++e) {
    const std::string context = "entry " + std::to_string(e);
    expect_same(read_back(given, e, vocabulary.word_count()), bows[e], context);
    expect_same(read_back(found_again, e, vocabulary.word_count()), bows[e], context);
  }
}

// A vector as transform would make it under L1 scoring, from word counts:
// float(weight * count / divisor), the divisor the weighted counts' sum in
// word order.
BowVector counted_vector(const Vocabulary& vocabulary,
                         const std::map<WordId, std::uint32_t>& counts) {
  double divisor = 0;
  for (const auto& [word, count] : counts)
    divisor += static_cast<double>(vocabulary.word_weight(word)) * count;
  std::vector<BowEntry> entries;
  for (const auto& [word, count] : counts)
    entries.push_back({word, static_cast<float>(static_cast<double>(vocabulary.word_weight(word)) *
                                                count / divisor)});
  return BowVector(std::move(entries));
}

TEST(ForwardIndex, AddsAfterTheFirstFastQueryAnswerAsADatabaseBuiltAtOnce) {
  // One database is queried in fast mode early, so that its later adds and
  // removals keep its forward index up to date; the other builds its
  // forward index at the end. Images of 300 places share most of their
  // words, ~1.7M postings per query: enough that fast mode scores candidates
  // from the forward index. Both must answer alike, with exact scores.
  const Vocabulary vocabulary = trained_vocabulary(Weighting::kTfIdf);
  std::vector<WordId> words;  // of positive weight: Zipf-drawn, word 0 the most common
  for (WordId w = 0; w < vocabulary.word_count(); ++w)
    if (vocabulary.word_weight(w) > 0) words.push_back(w);
  ASSERT_GT(words.size(), 1000u);
  std::mt19937_64 rng(12);
  std::vector<double> cumulative;
  double total = 0;
  for (std::size_t i = 0; i < words.size(); ++i) cumulative.push_back(total += 1.0 / (i + 1.0));
  const auto draw = [&] {
    const double u = std::uniform_real_distribution<double>(0, total)(rng);
    return words[static_cast<std::size_t>(
        std::lower_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin())];
  };
  std::vector<std::map<WordId, std::uint32_t>> places(300);
  for (auto& place : places)
    for (int i = 0; i < 450; ++i) ++place[draw()];
  const auto image_of = [&](std::size_t place) {
    std::map<WordId, std::uint32_t> counts;
    for (const auto& [word, count] : places[place])
      if (rng() % 5 != 0) counts[word] += count;
    for (int i = 0; i < 80; ++i) ++counts[draw()];
    return counts;
  };
  std::vector<BowVector> bows;
  for (std::size_t i = 0; i < 28'000; ++i) {
    std::map<WordId, std::uint32_t> counts = image_of(i % places.size());
    if (i % 5'000 == 7) counts[words[9]] += 300;  // beyond a segment row's counts
    bows.push_back(counted_vector(vocabulary, counts));
  }
  bows[11] = BowVector({{words[0], 0.25f}, {words[7], 0.5f}, {words[100], 1.5f}});  // floats
  std::vector<bool> live(bows.size(), true);

  const QueryOptions fast{QueryMode::kFast, 1};
  Database early(vocabulary, DatabaseOptions{false, 0});
  Database late(vocabulary, DatabaseOptions{false, 0});
  std::size_t added = 0;
  const auto add = [&](std::size_t end) {
    for (; added < end; ++added) {
      EXPECT_EQ(early.add(bows[added]), added);
      EXPECT_EQ(late.add(bows[added]), added);
    }
  };
  const auto remove = [&](EntryId entry) {
    early.remove(entry);
    late.remove(entry);
    live[entry] = false;
  };
  add(5);
  EXPECT_FALSE(early.query(bows[1], 10, kAllEntries, fast).empty());
  add(9'000);
  for (EntryId e = 1; e < added; e += 4) remove(e);
  add(bows.size());
  remove(static_cast<EntryId>(bows.size() - 1));
  for (std::size_t q = 0; q < 20; ++q) {
    const BowVector query = counted_vector(vocabulary, image_of(q * 7));
    const std::string context = "query " + std::to_string(q);
    const std::vector<QueryResult> expected = late.query(query, 10, kAllEntries, fast);
    const std::vector<QueryResult> actual = early.query(query, 10, kAllEntries, fast);
    ASSERT_EQ(actual.size(), 10u) << context;
    ASSERT_EQ(expected.size(), 10u) << context;
    for (std::size_t i = 0; i < actual.size(); ++i) {
      EXPECT_EQ(actual[i].entry, expected[i].entry) << context << " rank " << i;
      EXPECT_EQ(actual[i].score, expected[i].score) << context << " rank " << i;
      EXPECT_EQ(actual[i].shared_words, expected[i].shared_words) << context << " rank " << i;
      EXPECT_TRUE(live[actual[i].entry]) << context << " rank " << i;
      EXPECT_EQ(actual[i].score, score_bow(query, bows[actual[i].entry], Scoring::kL1))
          << context << " rank " << i;
    }
  }
}

}  // namespace
}  // namespace binbow
