// The forward index that fast queries score their candidates from gives
// back every entry's words and weights bit for bit, in about 2 bytes per word
// for vectors made by Vocabulary::transform.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/vocabulary.h"
#include "database/count_form.h"
#include "database/forward_index.h"
#include "support/random_tree.h"
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

// Runs `body` with the forward index's portable look-up and with the
// fastest the CPU has (the same where it has no vector code).
template <class Body>
void with_each_look_up(Body&& body) {
  for (const bool portable : {true, false}) {
    detail::portable_forward_lookups() = portable;
    body(std::string(portable ? "portable" : "fastest"));
  }
  detail::portable_forward_lookups() = false;
}

// A query word set over `words`, with the weights for_each_shared needs.
struct Query {
  detail::QueryWordSet set;
  std::vector<double> weights;
  Query(const detail::ForwardIndex& index, const std::vector<BowEntry>& words) {
    set.assign(Span<BowEntry>(words.data(), words.size()));
    for (const BowEntry& e : words) weights.push_back(index.word_weight(e.word));
  }
};

// What for_each_shared gives: (q, weight) in order.
std::vector<BowEntry> shared_words(const detail::ForwardIndex& index, EntryId entry,
                                   const Query& query) {
  std::vector<std::uint32_t> hits;
  std::vector<BowEntry> result;
  index.for_each_shared(entry, query.set, query.weights.data(), hits,
                        [&](std::uint32_t q, float weight) {
                          result.push_back({q, weight});
                        });
  return result;
}

// What for_each_shared gives for a query that holds every word id below
// `words`: the entry's (word, weight) in order.
std::vector<BowEntry> read_back(const detail::ForwardIndex& index, EntryId entry,
                                std::size_t words) {
  std::vector<BowEntry> all;
  for (WordId w = 0; w < words; ++w) all.push_back({w, 1.0f});
  return shared_words(index, entry, Query(index, all));
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
      with_each_look_up([&](const std::string& look_up) {
        for (EntryId e = 0; e < bows.size(); ++e)
          expect_same(read_back(index, e, vocabulary.word_count()), bows[e],
                      context + " " + look_up + " entry " + std::to_string(e));
      });
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
      BowVector({{0, 0.25f}, {1, 0.5f}, {70'000, -1.5f}, {40'000'000u, 3e-30f}}),
      BowVector({{5, 1.0f}}),
      BowVector(),
      BowVector({{32'767, 0.125f}, {65'535, 0.75f}, {65'536, 0.0f}}),
  };
  for (const bool over_word_ids : {true, false}) {
    detail::ForwardIndex index(over_word_ids ? nullptr : &vocabulary, Scoring::kL1);
    for (const BowVector& bow : bows) index.append(Span<BowEntry>(bow.begin(), bow.size()));
    index.append(Span<BowEntry>(bows[1].begin(), bows[1].size()));
    with_each_look_up([&](const std::string& look_up) {
      for (EntryId e = 0; e < bows.size(); ++e) {
        // The query is the entry itself: q is the word's index in it.
        const BowVector& bow = bows[e];
        std::vector<BowEntry> all =
            shared_words(index, e, Query(index, std::vector<BowEntry>(bow.begin(), bow.end())));
        for (BowEntry& word : all) word.word = bow[word.word].word;
        expect_same(all, bow, look_up + " entry " + std::to_string(e));
      }
    });
    index.drop(1);
    EXPECT_TRUE(shared_words(index, 1, Query(index, {{5, 1.0f}})).empty())
        << "a dropped entry has no words";
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

// The vector look-up (8 words at a time) against the portable one and a
// brute-force search: entries of every length (blocks of 8 and a tail),
// steps both sides of the 15-bit limit anywhere in a block, counts above 1,
// entries with floats; queries that hold about half of their words, some
// stopping below the entries' last words (a bitmap they run beyond).
TEST(ForwardIndex, VectorAndPortableLookUpsFindTheSameWords) {
  const Vocabulary vocabulary =
      Vocabulary::from_tree(test::complete_random_tree(10, 5, 32, 3));  // 100,000 words
  ASSERT_EQ(vocabulary.scoring(), Scoring::kL1);
  detail::ForwardIndex index(&vocabulary, Scoring::kL1);
  std::mt19937_64 rng(21);
  std::vector<BowVector> bows;
  std::size_t long_steps = 0;
  for (int i = 0; i < 80; ++i) {
    std::map<WordId, std::uint32_t> counts;
    const std::size_t words = rng() % 300;
    WordId word = static_cast<WordId>(rng() % 40'000);
    for (std::size_t k = 0; k < words && word < vocabulary.word_count(); ++k) {
      counts[word] = rng() % 4 == 0 ? 2 + static_cast<std::uint32_t>(rng() % 400) : 1;
      const bool long_step = rng() % 24 == 0;
      long_steps += long_step ? 1 : 0;
      word += long_step ? 32'766 + static_cast<WordId>(rng() % 4) : 1 + rng() % 40;
    }
    BowVector bow = counted_vector(vocabulary, counts);
    if (i % 4 == 3) {  // weights no vocabulary gives
      std::vector<BowEntry> floats(bow.begin(), bow.end());
      for (BowEntry& e : floats) e.value = std::uniform_real_distribution<float>(0.1f, 1.0f)(rng);
      bow = BowVector(std::move(floats));
    }
    index.append(Span<BowEntry>(bow.begin(), bow.size()));
    bows.push_back(std::move(bow));
  }
  ASSERT_GT(long_steps, 100u);
  for (int q = 0; q < 12; ++q) {
    const WordId end = q % 3 == 0 ? 60'000 : vocabulary.word_count();
    std::set<WordId> chosen;
    for (const BowVector& bow : bows)
      for (const BowEntry& e : bow)
        if (e.word < end && rng() % 2 == 0) chosen.insert(e.word);
    for (int extra = 0; extra < 500; ++extra) chosen.insert(static_cast<WordId>(rng() % end));
    std::vector<BowEntry> words;
    for (const WordId w : chosen) words.push_back({w, 1.0f});
    const Query query(index, words);
    for (EntryId e = 0; e < bows.size(); ++e) {
      std::vector<BowEntry> expected;
      for (const BowEntry& word : bows[e]) {
        const auto at = std::lower_bound(words.begin(), words.end(), word.word,
                                         [](const BowEntry& a, WordId w) { return a.word < w; });
        if (at != words.end() && at->word == word.word)
          expected.push_back({static_cast<WordId>(at - words.begin()), word.value});
      }
      with_each_look_up([&](const std::string& look_up) {
        expect_same(shared_words(index, e, query), BowVector(expected),
                    look_up + " query " + std::to_string(q) + " entry " + std::to_string(e));
      });
    }
  }
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
