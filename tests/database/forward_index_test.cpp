// The forward index that fast queries score their candidates from gives
// back every entry's words and weights bit for bit, in about 2 bytes per word
// for vectors made by Vocabulary::transform.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "binbow/vocabulary.h"
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

}  // namespace
}  // namespace binbow
