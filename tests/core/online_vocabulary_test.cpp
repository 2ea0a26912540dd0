#include "binbow/online_vocabulary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "core/crc32c.h"
#include "core/little_endian.h"
#include "core/sectioned_file.h"
#include "support/test_support.h"

namespace binbow {
namespace {

constexpr std::size_t kCode = 8;  // 64-bit descriptors: easy to craft

// Options for crafted 64-bit descriptors: a descriptor more than 8 bits from
// every word is a new word.
OnlineVocabularyOptions crafted_options() {
  OnlineVocabularyOptions options;
  options.new_word_distance = 8.0 / 64.0;
  options.purge_after_images = 0;
  options.exact = true;
  return options;
}

// `base` with bits [first, first + count) flipped.
std::vector<std::uint8_t> flipped(const std::vector<std::uint8_t>& base, std::size_t first,
                                  std::size_t count) {
  std::vector<std::uint8_t> out = base;
  for (std::size_t b = first; b < first + count; ++b) out[b / 8] ^= std::uint8_t(1u << (b % 8));
  return out;
}

DescriptorMatrix rows_of(const std::vector<std::vector<std::uint8_t>>& rows) {
  DescriptorMatrix matrix(kCode);
  for (const auto& row : rows) matrix.append(row.data());
  return matrix;
}

const std::vector<std::uint8_t> kZero(kCode, 0x00);
const std::vector<std::uint8_t> kOnes(kCode, 0xFF);

// The nearest live word by exhaustive search: lowest id on equal distances.
std::pair<WordId, std::uint32_t> brute_force(const OnlineVocabulary& vocabulary,
                                             const std::uint8_t* query) {
  std::pair<WordId, std::uint32_t> best{OnlineVocabulary::kNoWord, OnlineVocabulary::kNoWord};
  for (const WordId word : vocabulary.words()) {
    const std::uint32_t d =
        test::bit_distance(query, vocabulary.word_descriptor(word), vocabulary.code_size());
    if (d < best.second) best = {word, d};
  }
  return best;
}

TEST(OnlineVocabulary, RejectsOptionsOutOfRange) {
  const auto make = [](auto change) {
    OnlineVocabularyOptions options;
    change(options);
    return OnlineVocabulary(32, options);
  };
  EXPECT_THROW(OnlineVocabulary(0), InvalidArgument);
  EXPECT_THROW(OnlineVocabulary(1025), InvalidArgument);
  EXPECT_THROW(make([](auto& o) { o.new_word_distance = 1.5; }), InvalidArgument);
  EXPECT_THROW(make([](auto& o) { o.new_word_distance = std::nan(""); }), InvalidArgument);
  EXPECT_THROW(make([](auto& o) { o.trees = 0; }), InvalidArgument);
  EXPECT_THROW(make([](auto& o) { o.trees = 17; }), InvalidArgument);
  EXPECT_THROW(make([](auto& o) { o.branching = 1; }), InvalidArgument);
  EXPECT_THROW(make([](auto& o) { o.leaf_size = 0; }), InvalidArgument);
  EXPECT_THROW(make([](auto& o) { o.max_checks = 0; }), InvalidArgument);
  EXPECT_THROW(make([](auto& o) { o.descriptor = "Not-A-Name!"; }), InvalidArgument);
  EXPECT_NO_THROW(make([](auto&) {}));
}

TEST(OnlineVocabulary, FarDescriptorsBecomeWordsAndCloseOnesJoinThem) {
  OnlineVocabulary vocabulary(kCode, crafted_options());
  const OnlineImageWords first =
      vocabulary.add_image(rows_of({kZero, kOnes, flipped(kZero, 0, 8)}));
  // The third is 8 bits from word 0: not farther than the threshold, joins it.
  EXPECT_EQ(first.words, (std::vector<WordId>{0, 1, 0}));
  EXPECT_EQ(first.new_words, 2u);
  EXPECT_EQ(vocabulary.word_count(), 2u);

  const OnlineImageWords second = vocabulary.add_image(rows_of({flipped(kOnes, 0, 9), kOnes}));
  EXPECT_EQ(second.words, (std::vector<WordId>{2, 1}));  // 9 bits: a new word
  EXPECT_EQ(vocabulary.next_word_id(), 3u);

  const OnlineWordInfo zero = vocabulary.word_info(0);
  EXPECT_EQ(zero.images, 1u);
  EXPECT_EQ(zero.observations, 2u);
  const OnlineWordInfo ones = vocabulary.word_info(1);
  EXPECT_EQ(ones.images, 2u);
  EXPECT_EQ(ones.observations, 2u);
  EXPECT_EQ(ones.first_image, 0u);
  EXPECT_EQ(ones.last_image, 1u);
  EXPECT_THROW(vocabulary.add_image(DescriptorMatrix(1, 32)), InvalidArgument);
  EXPECT_EQ(vocabulary.image_count(), 2u);  // unchanged by the rejected image
}

TEST(OnlineVocabulary, WordsFollowTheBitwiseMajorityOfTheirDescriptors) {
  OnlineVocabulary vocabulary(kCode, crafted_options());
  const std::vector<std::uint8_t> moved = flipped(kZero, 0, 4);
  vocabulary.add_image(rows_of({kZero}));
  vocabulary.add_image(rows_of({moved}));
  // One descriptor each way: a tie keeps the word's bits.
  EXPECT_EQ(std::memcmp(vocabulary.word_descriptor(0), kZero.data(), kCode), 0);
  vocabulary.add_image(rows_of({moved}));
  // Two of three descriptors have bits 0..3 set: the word takes them.
  EXPECT_EQ(std::memcmp(vocabulary.word_descriptor(0), moved.data(), kCode), 0);
  EXPECT_EQ(vocabulary.word_count(), 1u);
  EXPECT_EQ(vocabulary.word_info(0).observations, 3u);
}

TEST(OnlineVocabulary, MajorityCountersSurviveManyObservations) {
  // Past 255 descriptors the counters halve; the majority still follows.
  OnlineVocabulary vocabulary(kCode, crafted_options());
  const std::vector<std::uint8_t> moved = flipped(kZero, 10, 3);
  for (int i = 0; i < 300; ++i) vocabulary.add_image(rows_of({kZero}));
  EXPECT_EQ(std::memcmp(vocabulary.word_descriptor(0), kZero.data(), kCode), 0);
  for (int i = 0; i < 400; ++i) vocabulary.add_image(rows_of({moved}));
  EXPECT_EQ(std::memcmp(vocabulary.word_descriptor(0), moved.data(), kCode), 0);
  EXPECT_EQ(vocabulary.word_info(0).observations, 700u);
}

TEST(OnlineVocabulary, WordsSeenInOneImageArePurgedAndTheirIdsNeverReused) {
  OnlineVocabularyOptions options = crafted_options();
  options.purge_after_images = 2;
  OnlineVocabulary vocabulary(kCode, options);
  const auto a = kZero, b = kOnes, c = flipped(kZero, 16, 32);
  EXPECT_TRUE(vocabulary.add_image(rows_of({a, b})).purged.empty());  // image 0: words 0, 1
  EXPECT_TRUE(vocabulary.add_image(rows_of({b})).purged.empty());     // image 1: 1 seen twice
  const OnlineImageWords third = vocabulary.add_image(rows_of({c}));  // image 2: word 2
  EXPECT_EQ(third.purged, (std::vector<WordId>{0}));                  // two images later, seen once
  EXPECT_FALSE(vocabulary.contains(0));
  EXPECT_TRUE(vocabulary.contains(1));
  EXPECT_THROW(vocabulary.word_info(0), InvalidArgument);

  // The purged word's descriptor comes back as a new id.
  const OnlineImageWords fourth = vocabulary.add_image(rows_of({a}));
  EXPECT_EQ(fourth.words, (std::vector<WordId>{3}));
  EXPECT_TRUE(fourth.purged.empty());
  const OnlineImageWords fifth = vocabulary.add_image(rows_of({b}));
  EXPECT_EQ(fifth.purged, (std::vector<WordId>{2}));
  EXPECT_EQ(vocabulary.words(), (std::vector<WordId>{1, 3}));
  EXPECT_EQ(vocabulary.stats().purged_words, 2u);
}

TEST(OnlineVocabulary, WeightsAreTfIdfOfTheImagesSeenL1Normalised) {
  OnlineVocabulary vocabulary(kCode, crafted_options());
  const auto a = kZero, b = kOnes, c = flipped(kZero, 16, 32);
  vocabulary.add_image(rows_of({a, b}));
  vocabulary.add_image(rows_of({a, c}));
  vocabulary.add_image(rows_of({c}));
  // N = 3; word 0 (a) in 2 images, word 1 (b) in 1, word 2 (c) in 2.
  EXPECT_DOUBLE_EQ(vocabulary.idf(1), std::log(3.0));
  EXPECT_DOUBLE_EQ(vocabulary.idf(0), std::log(1.5));

  BowVector bow;
  FeatureVector features;
  vocabulary.transform(rows_of({b, a, a, flipped(kOnes, 0, 20)}), bow, &features);
  // The last descriptor is 20 bits from every word: it would be a new word
  // that no image contains, so it is left out.
  const double va = 2 * std::log(1.5), vb = std::log(3.0);
  ASSERT_EQ(bow.size(), 2u);
  EXPECT_EQ(bow[0].word, 0u);
  EXPECT_FLOAT_EQ(bow[0].value, static_cast<float>(va / (va + vb)));
  EXPECT_EQ(bow[1].word, 1u);
  EXPECT_FLOAT_EQ(bow[1].value, static_cast<float>(vb / (va + vb)));
  // The direct index's node is the word itself.
  ASSERT_EQ(features.size(), 2u);
  EXPECT_EQ(features.node(0), 0u);
  EXPECT_EQ(std::vector<std::uint32_t>(features.features(0).begin(), features.features(0).end()),
            (std::vector<std::uint32_t>{1, 2}));
  EXPECT_EQ(features.node(1), 1u);

  // A word in every image weighs 0 and is dropped, as Vocabulary drops stop words.
  OnlineVocabulary everywhere(kCode, crafted_options());
  everywhere.add_image(rows_of({a}));
  everywhere.add_image(rows_of({a, b}));
  everywhere.transform(rows_of({a}), bow, &features);
  EXPECT_TRUE(bow.empty());
  EXPECT_TRUE(features.empty());
}

TEST(OnlineVocabulary, ExactSearchEqualsBruteForce) {
  std::mt19937_64 rng(7);
  OnlineVocabularyOptions options;
  options.exact = true;
  options.new_word_distance = 0.35;
  OnlineVocabulary vocabulary(32, options);
  for (int image = 0; image < 20; ++image)
    vocabulary.add_image(test::clustered_descriptors(100, 32, 40, 0.1, rng));
  const DescriptorMatrix queries = test::random_descriptors(300, 32, rng);
  std::vector<WordId> words(queries.rows());
  std::vector<std::uint32_t> distances(queries.rows());
  vocabulary.nearest_words(queries, words.data(), distances.data());
  for (std::size_t i = 0; i < queries.rows(); ++i) {
    const auto expected = brute_force(vocabulary, queries.row(i));
    EXPECT_EQ(words[i], expected.first) << "query " << i;
    EXPECT_EQ(distances[i], expected.second) << "query " << i;
  }
}

struct Recall {
  double nearest = 0;   // found a word as near as the nearest
  double decision = 0;  // new word or not, as exhaustive search decides
};

// The approximate search against brute force for `queries`.
Recall recall(const OnlineVocabulary& vocabulary, const DescriptorView& queries) {
  std::vector<WordId> words(queries.rows);
  std::vector<std::uint32_t> distances(queries.rows);
  vocabulary.nearest_words(queries, words.data(), distances.data());
  const auto new_word_bits = static_cast<std::uint32_t>(vocabulary.options().new_word_distance *
                                                        static_cast<double>(queries.code_size * 8));
  std::size_t nearest = 0, decision = 0;
  for (std::size_t i = 0; i < queries.rows; ++i) {
    const auto expected = brute_force(vocabulary, queries.row(i));
    EXPECT_GE(distances[i], expected.second);
    EXPECT_EQ(distances[i],
              test::bit_distance(queries.row(i), vocabulary.word_descriptor(words[i]), 32));
    nearest += distances[i] == expected.second;
    decision += (distances[i] <= new_word_bits) == (expected.second <= new_word_bits);
  }
  const auto rows = static_cast<double>(queries.rows);
  return {static_cast<double>(nearest) / rows, static_cast<double>(decision) / rows};
}

TEST(OnlineVocabulary, ApproximateSearchAgreesWithBruteForceOnClusteredDescriptors) {
  // Descriptors near 2,000 centres, 10% of bits flipped (about 26 bits
  // from their centre, as close matches of real ORB features are), after
  // the trees have been split and rebuilt many times. The documented rates
  // (docs/online-vocabulary.md), a little lowered so that the test does not
  // depend on the last digit.
  std::mt19937_64 rng(11);
  const DescriptorMatrix all = test::clustered_descriptors(60000, 32, 2000, 0.1, rng);
  OnlineVocabularyOptions options;
  options.purge_after_images = 0;
  OnlineVocabulary vocabulary(32, options);
  for (std::size_t image = 0; image < 50; ++image)
    vocabulary.add_image(all.view().slice(image * 1000, 1000));
  EXPECT_GE(vocabulary.stats().tree_rebuilds, 3u * options.trees);
  const Recall measured = recall(vocabulary, all.view().slice(50000, 2000));
  EXPECT_GE(measured.nearest, 0.82);
  EXPECT_GE(measured.decision, 0.90);
  std::printf("clustered: %zu words, nearest %.4f, same new-word decision %.4f\n",
              vocabulary.word_count(), measured.nearest, measured.decision);
}

TEST(OnlineVocabulary, SameImagesGiveTheSameWords) {
  std::mt19937_64 rng(3);
  const DescriptorMatrix all = test::clustered_descriptors(30 * 300, 32, 200, 0.08, rng);
  std::vector<DescriptorView> images;
  for (std::size_t i = 0; i < 30; ++i) images.push_back(all.view().slice(i * 300, 300));
  OnlineVocabularyOptions options;
  options.purge_after_images = 5;
  options.leaf_size = 16;  // many splits
  OnlineVocabulary first(32, options), second(32, options);
  for (const DescriptorView& image : images) {
    const OnlineImageWords a = first.add_image(image);
    const OnlineImageWords b = second.add_image(image);
    ASSERT_EQ(a.words, b.words);
    ASSERT_EQ(a.purged, b.purged);
  }
  EXPECT_GT(first.stats().purged_words, 0u);
  EXPECT_EQ(first.serialize(), second.serialize());

  options.seed = 99;  // other trees: the search may differ, the rules do not
  OnlineVocabulary reseeded(32, options);
  for (const DescriptorView& image : images) reseeded.add_image(image);
  EXPECT_GT(reseeded.word_count(), 0u);
}

constexpr std::size_t kSections = 10;  // in a .bbov of version 2

class OnlineVocabularyFile : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937_64 rng(5);
    OnlineVocabularyOptions options;
    options.purge_after_images = 4;
    options.descriptor = "orb";
    options.leaf_size = 4;  // trees several levels deep
    vocabulary_ = std::make_unique<OnlineVocabulary>(32, options);
    all_ = test::clustered_descriptors(12 * 200, 32, 150, 0.06, rng);
    for (std::size_t i = 0; i < 12; ++i) {
      images_.push_back(all_.view().slice(i * 200, 200));
      if (i < 8) vocabulary_->add_image(images_.back());
    }
    bytes_ = vocabulary_->serialize();
  }

  // Recomputes every CRC so that a change reaches the checks behind them.
  static void fix_checksums(std::vector<std::uint8_t>& bytes) {
    const std::size_t sections = detail::load_le<std::uint32_t>(bytes.data() + 48);
    const std::size_t table_size = sections * 24;
    std::uint8_t* table = bytes.data() + 64;
    for (std::size_t i = 0; i < sections; ++i) {
      std::uint8_t* e = table + i * 24;
      const auto offset = detail::load_le<std::uint64_t>(e + 8);
      const auto length = detail::load_le<std::uint64_t>(e + 16);
      if (offset <= bytes.size() && length <= bytes.size() - offset)
        detail::store_le<std::uint32_t>(e + 4, detail::crc32c(bytes.data() + offset, length));
    }
    detail::store_le<std::uint32_t>(table + table_size, detail::crc32c(table, table_size));
    detail::store_le<std::uint32_t>(bytes.data() + 60, detail::crc32c(bytes.data(), 60));
  }

  // The offset and length of section `index` of a .bbov image.
  static std::pair<std::size_t, std::size_t> section(const std::vector<std::uint8_t>& bytes,
                                                     std::size_t index) {
    const std::uint8_t* entry = bytes.data() + 64 + index * 24;
    return {detail::load_le<std::uint64_t>(entry + 8), detail::load_le<std::uint64_t>(entry + 16)};
  }

  std::string rejection(const std::vector<std::uint8_t>& bytes) {
    try {
      OnlineVocabulary::deserialize(bytes.data(), bytes.size(), "state.bbov");
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), "state.bbov");
      return e.problem();
    }
    return "accepted";
  }

  // Two vocabularies restored from one file continue alike from image
  // `first` on: the same words and purges, and in the end the same state.
  void expect_same_continuation(OnlineVocabulary& a, OnlineVocabulary& b, std::size_t first) {
    for (std::size_t i = first; i < images_.size(); ++i) {
      const OnlineImageWords from_a = a.add_image(images_[i]);
      const OnlineImageWords from_b = b.add_image(images_[i]);
      ASSERT_EQ(from_a.words, from_b.words) << "image " << i;
      ASSERT_EQ(from_a.purged, from_b.purged) << "image " << i;
    }
    EXPECT_EQ(a.serialize(), b.serialize());
  }

  std::unique_ptr<OnlineVocabulary> vocabulary_;
  DescriptorMatrix all_;
  std::vector<DescriptorView> images_;
  std::vector<std::uint8_t> bytes_;
};

TEST_F(OnlineVocabularyFile, RoundTripRestoresTheWordsAndContinuesTheSameWay) {
  test::TempDir dir;
  vocabulary_->save(dir.file("state.bbov"));
  OnlineVocabulary loaded = OnlineVocabulary::load(dir.file("state.bbov"));
  EXPECT_EQ(loaded.serialize(), bytes_);
  EXPECT_EQ(loaded.words(), vocabulary_->words());
  EXPECT_EQ(loaded.options().descriptor, "orb");
  for (const WordId word : loaded.words()) {
    EXPECT_EQ(std::memcmp(loaded.word_descriptor(word), vocabulary_->word_descriptor(word), 32), 0);
    EXPECT_EQ(loaded.word_info(word).observations, vocabulary_->word_info(word).observations);
  }
  BowVector expected, actual;
  vocabulary_->transform(images_[9], expected);
  loaded.transform(images_[9], actual);
  EXPECT_GT(actual.size(), 0u);

  // Every restore of the file continues alike, purges included.
  OnlineVocabulary again = OnlineVocabulary::deserialize(bytes_.data(), bytes_.size(), "again");
  expect_same_continuation(loaded, again, 8);
}

TEST_F(OnlineVocabularyFile, ExactModeContinuesExactlyAsTheSavedVocabulary) {
  OnlineVocabularyOptions options;
  options.exact = true;
  options.purge_after_images = 3;
  OnlineVocabulary original(32, options);
  for (int i = 0; i < 6; ++i) original.add_image(images_[i]);
  const std::vector<std::uint8_t> saved = original.serialize();
  OnlineVocabulary restored = OnlineVocabulary::deserialize(saved.data(), saved.size(), "exact");
  for (std::size_t i = 6; i < images_.size(); ++i) {
    const OnlineImageWords a = original.add_image(images_[i]);
    const OnlineImageWords b = restored.add_image(images_[i]);
    ASSERT_EQ(a.words, b.words);
    ASSERT_EQ(a.purged, b.purged);
  }
}

TEST_F(OnlineVocabularyFile, EveryTruncationIsRejected) {
  for (std::size_t size = 0; size < bytes_.size(); size += size < 300 ? 1 : 97) {
    const std::vector<std::uint8_t> cut(bytes_.begin(), bytes_.begin() + size);
    EXPECT_NE(rejection(cut), "accepted") << size << " bytes";
  }
  EXPECT_NE(rejection({}).find("truncated"), std::string::npos);
}

TEST_F(OnlineVocabularyFile, FlippedBytesAreRejected) {
  for (std::size_t at = 0; at < bytes_.size(); at += at < 400 ? 1 : 37) {
    std::vector<std::uint8_t> damaged = bytes_;
    damaged[at] ^= 0x10;
    EXPECT_NE(rejection(damaged), "accepted") << "byte " << at;
  }
  std::vector<std::uint8_t> damaged = bytes_;
  damaged[bytes_.size() - 3] ^= 1;  // inside the last section
  EXPECT_NE(rejection(damaged).find("checksum mismatch in section"), std::string::npos);
}

TEST_F(OnlineVocabularyFile, ClearErrorsForWrongMagicVersionAndHugeCounts) {
  std::vector<std::uint8_t> bytes = bytes_;
  bytes[0] = 'X';
  EXPECT_NE(rejection(bytes).find("wrong magic"), std::string::npos);

  bytes = bytes_;
  detail::store_le<std::uint32_t>(bytes.data() + 8, 3);
  fix_checksums(bytes);
  EXPECT_NE(rejection(bytes).find("unsupported .bbov format version 3"), std::string::npos);

  // Counts that would need gigabytes: rejected against the sections' sizes
  // before anything is allocated.
  bytes = bytes_;
  detail::store_le<std::uint32_t>(bytes.data() + 24, 0xFFFFFFF0u);  // ids created
  detail::store_le<std::uint32_t>(bytes.data() + 28, 0xFFFFFFF0u);  // live words
  fix_checksums(bytes);
  EXPECT_NE(rejection(bytes).find("inconsistent word counts"), std::string::npos);

  bytes = bytes_;
  const auto words = detail::load_le<std::uint32_t>(bytes.data() + 28);
  detail::store_le<std::uint32_t>(bytes.data() + 24, 0xFFFFFFF0u);
  detail::store_le<std::uint64_t>(bytes.data() + 40, 0xFFFFFFF0u - words);
  fix_checksums(bytes);
  EXPECT_EQ(rejection(bytes), "accepted");  // ids purged cost no memory

  bytes = bytes_;
  ASSERT_GT(detail::load_le<std::uint32_t>(bytes.data() + 32), 0u);  // words with counters
  detail::store_le<std::uint32_t>(bytes.data() + 32, 0);
  fix_checksums(bytes);
  EXPECT_NE(rejection(bytes).find("section 'counters' has"), std::string::npos);

  bytes = bytes_;
  detail::store_le<std::uint32_t>(bytes.data() + 16, 64);  // another descriptor size
  fix_checksums(bytes);
  EXPECT_NE(rejection(bytes).find("section 'descriptors' has"), std::string::npos);
}

TEST_F(OnlineVocabularyFile, StatesAtTheCountersLimitsRefuseImagesUnchanged) {
  const auto words = detail::load_le<std::uint32_t>(bytes_.data() + 28);
  std::vector<std::uint8_t> bytes = bytes_;
  // One word id left, so an image of two descriptors might need too many.
  detail::store_le<std::uint32_t>(bytes.data() + 24, OnlineVocabulary::kNoWord - 1);
  detail::store_le<std::uint64_t>(bytes.data() + 40, OnlineVocabulary::kNoWord - 1 - words);
  fix_checksums(bytes);
  OnlineVocabulary full = OnlineVocabulary::deserialize(bytes.data(), bytes.size(), "ids.bbov");
  EXPECT_THROW(full.add_image(images_[9].slice(0, 2)), InvalidArgument);
  EXPECT_EQ(full.serialize(), bytes);
  EXPECT_EQ(full.add_image(images_[9].slice(0, 1)).words.size(), 1u);

  bytes = bytes_;
  detail::store_le<std::uint32_t>(bytes.data() + 20, 0xFFFFFFFFu);  // images added
  fix_checksums(bytes);
  OnlineVocabulary old = OnlineVocabulary::deserialize(bytes.data(), bytes.size(), "old.bbov");
  EXPECT_THROW(old.add_image(images_[9]), InvalidArgument);
  EXPECT_EQ(old.serialize(), bytes);
}

TEST_F(OnlineVocabularyFile, InconsistentWordsAreRejected) {
  // Word counts live in section 2, after options (48 + 3 bytes) and ids.
  const auto words = detail::load_le<std::uint32_t>(bytes_.data() + 28);
  const std::size_t counts_offset = 64 + kSections * 24 + 4 + 48 + 3 + std::size_t{words} * 4;
  std::vector<std::uint8_t> bytes = bytes_;
  detail::store_le<std::uint32_t>(bytes.data() + counts_offset, 0);  // seen in no image
  fix_checksums(bytes);
  EXPECT_NE(rejection(bytes).find("inconsistent counts"), std::string::npos);

  bytes = bytes_;
  const std::size_t ids_offset = 64 + kSections * 24 + 4 + 48 + 3;
  std::memcpy(bytes.data() + ids_offset + 4, bytes.data() + ids_offset, 4);  // an id twice
  fix_checksums(bytes);
  EXPECT_NE(rejection(bytes).find("appears twice"), std::string::npos);

  bytes = bytes_;
  bytes[64 + kSections * 24 + 4 + 12] = 0;  // zero trees
  fix_checksums(bytes);
  EXPECT_NE(rejection(bytes).find("invalid options"), std::string::npos);
}

// The acceptance test of saved search trees: a vocabulary saved and loaded
// every few images, approximate search, continues exactly as one never saved
// (words, new words, purges, lookups), through splits, rebuilds and purges.
TEST(OnlineVocabulary, SavedAndLoadedAtManyPointsContinuesAsNeverSaved) {
  std::mt19937_64 rng(21);
  const std::size_t per_image = 250;
  const std::size_t image_count = 40;
  const DescriptorMatrix all =
      test::clustered_descriptors((image_count + 1) * per_image, 32, 1500, 0.12, rng);
  const DescriptorView queries = all.view().slice(image_count * per_image, per_image);
  OnlineVocabularyOptions options;
  options.purge_after_images = 3;
  options.leaf_size = 16;   // many splits
  options.max_checks = 16;  // a coarse search: any change of tree shows
  OnlineVocabulary never_saved(32, options);
  OnlineVocabulary resumed(32, options);
  std::size_t loads = 0;
  for (std::size_t i = 0; i < image_count; ++i) {
    SCOPED_TRACE("image " + std::to_string(i));
    if (i % 6 == 1) {
      const std::vector<std::uint8_t> bytes = resumed.serialize();
      resumed = OnlineVocabulary::deserialize(bytes.data(), bytes.size(), "resumed.bbov");
      ASSERT_EQ(resumed.serialize(), bytes) << "a loaded vocabulary saves the same bytes";
      ++loads;
    }
    const DescriptorView image = all.view().slice(i * per_image, per_image);
    const OnlineImageWords expected = never_saved.add_image(image);
    const OnlineImageWords actual = resumed.add_image(image);
    ASSERT_EQ(actual.words, expected.words);
    ASSERT_EQ(actual.new_words, expected.new_words);
    ASSERT_EQ(actual.purged, expected.purged);

    std::vector<WordId> expected_words(queries.rows), actual_words(queries.rows);
    std::vector<std::uint32_t> expected_distances(queries.rows), actual_distances(queries.rows);
    never_saved.nearest_words(queries, expected_words.data(), expected_distances.data());
    resumed.nearest_words(queries, actual_words.data(), actual_distances.data());
    ASSERT_EQ(actual_words, expected_words);
    ASSERT_EQ(actual_distances, expected_distances);
  }
  EXPECT_EQ(loads, 7u);
  EXPECT_GE(never_saved.stats().tree_rebuilds, 3u * options.trees) << "rebuilds after loads";
  EXPECT_GT(never_saved.stats().purged_words, 0u);
  EXPECT_EQ(resumed.serialize(), never_saved.serialize());
}

TEST_F(OnlineVocabularyFile, Version1FilesStillLoadWithTreesRebuiltFromTheWords) {
  // bytes_ as version 1 wrote them: the same header and first six sections,
  // no trees.
  std::vector<std::vector<std::uint8_t>> sections;
  for (std::size_t i = 0; i < 6; ++i) {
    const auto [offset, length] = section(bytes_, i);
    sections.emplace_back(bytes_.begin() + offset, bytes_.begin() + offset + length);
  }
  const std::vector<std::uint8_t> version1 =
      detail::write_sectioned_file("BINBOWOV", 1, sections.data(), 6, [&](std::uint8_t* header) {
        std::memcpy(header + 16, bytes_.data() + 16, 32);
        std::memcpy(header + 52, bytes_.data() + 52, 8);
      });
  OnlineVocabulary loaded = OnlineVocabulary::deserialize(version1.data(), version1.size(), "v1");
  EXPECT_EQ(loaded.words(), vocabulary_->words());
  for (const WordId word : loaded.words())
    EXPECT_EQ(std::memcmp(loaded.word_descriptor(word), vocabulary_->word_descriptor(word), 32), 0);
  EXPECT_EQ(detail::load_le<std::uint32_t>(loaded.serialize().data() + 8), 2u)
      << "saved again, it is a version-2 file";

  // Every load of the file continues alike.
  OnlineVocabulary again = OnlineVocabulary::deserialize(version1.data(), version1.size(), "v1");
  expect_same_continuation(loaded, again, 8);
}

TEST_F(OnlineVocabularyFile, MalformedTreesAreRefusedEvenWithValidChecksums) {
  const std::size_t trees_at = section(bytes_, 6).first;
  const std::size_t nodes_at = section(bytes_, 7).first;
  const std::size_t leaves_at = section(bytes_, 9).first;
  const auto node_count = detail::load_le<std::uint32_t>(bytes_.data() + trees_at);
  // Tree 0's node records: first child, child count, leaf words.
  const auto field = [&](std::uint32_t node, std::size_t index) {
    return nodes_at + std::size_t{node} * 12 + index * 4;
  };
  const auto root_children = detail::load_le<std::uint32_t>(bytes_.data() + field(0, 1));
  ASSERT_GT(root_children, 2u);
  ASSERT_GT(node_count, root_children + 1) << "tree 0 must be deeper than its root's children";
  std::uint32_t first_leaf = 0;
  while (detail::load_le<std::uint32_t>(bytes_.data() + field(first_leaf, 2)) == 0) ++first_leaf;

  const auto refused_with = [&](const std::function<void(std::vector<std::uint8_t>&)>& change,
                                const std::string& expected) {
    std::vector<std::uint8_t> bytes = bytes_;
    change(bytes);
    fix_checksums(bytes);
    const std::string problem = rejection(bytes);
    EXPECT_NE(problem.find(expected), std::string::npos)
        << "expected \"" << expected << "\", got: " << problem;
  };
  const auto set = [](std::size_t at, std::uint32_t value) {
    return [=](std::vector<std::uint8_t>& bytes) {
      detail::store_le<std::uint32_t>(bytes.data() + at, value);
    };
  };
  // Counts that would need gigabytes, or no root at all.
  refused_with(set(trees_at, 0xFFFFFFF0u), "section 'tree nodes' has");
  refused_with(set(trees_at, 0), "tree 0 has no root");
  refused_with(set(trees_at + 4, 0xFFFFFFF0u), "built over more words");
  // A child index out of range, a cycle (children before their parent),
  // too many children, a node with two parents, one with none.
  refused_with(set(field(0, 0), node_count), "children are out of range");
  refused_with(set(field(0, 0), 0), "must come after its parent");
  refused_with(set(field(0, 1), 17), "has 17 children, expected 2 to 16");
  refused_with(set(field(0, 0), 2), "has two parents");
  refused_with(set(field(0, 1), root_children - 1), "is not in the tree");
  refused_with(set(field(0, 2), 1), "an inner node that lists words");
  refused_with(set(field(first_leaf, 0), 1), "is a leaf with a first child");
  // A word missing from a tree, listed twice, or out of range.
  const auto leaf_words = detail::load_le<std::uint32_t>(bytes_.data() + field(first_leaf, 2));
  refused_with(set(field(first_leaf, 2), leaf_words - 1), "is missing 1 word(s)");
  refused_with(set(field(first_leaf, 2), 0xFFFFFFF0u), "lists more words in its leaves");
  refused_with(
      [&](std::vector<std::uint8_t>& bytes) {
        std::memcpy(bytes.data() + leaves_at + 4, bytes.data() + leaves_at, 4);
      },
      "twice");
  refused_with(set(leaves_at, 0xFFFFFFF0u), "beyond the");
}

TEST(OnlineVocabularyExport, GrownWordsBecomeAFixedVocabulary) {
  std::mt19937_64 rng(13);
  OnlineVocabularyOptions options;
  options.descriptor = "orb";
  OnlineVocabulary online(32, options);
  const DescriptorMatrix all = test::clustered_descriptors(10 * 300, 32, 500, 0.05, rng);
  std::vector<DescriptorView> images;
  for (std::size_t i = 0; i < 10; ++i) {
    images.push_back(all.view().slice(i * 300, 300));
    online.add_image(images.back());
  }
  BuildOptions build;
  build.branching = 8;
  build.levels = 4;
  build.threads = 1;
  const Vocabulary fixed = online.to_vocabulary(build);
  EXPECT_EQ(fixed.descriptor(), "orb");
  EXPECT_EQ(fixed.weighting(), Weighting::kTfIdf);
  EXPECT_EQ(fixed.code_size(), 32u);
  EXPECT_GT(fixed.word_count(), online.word_count() / 4);
  // A word seen in few images weighs more than one seen in many, as online.
  std::size_t positive = 0;
  for (WordId word = 0; word < fixed.word_count(); ++word) {
    EXPECT_GE(fixed.word_weight(word), 0.0f);
    EXPECT_LE(fixed.word_weight(word), std::log(10.0) + 1e-6);
    positive += fixed.word_weight(word) > 0;
  }
  EXPECT_GT(positive, 0u);
  // Images score with themselves as well as with the online vocabulary.
  BowVector a, b;
  fixed.transform(images[3], a);
  fixed.transform(images[3], b);
  EXPECT_NEAR(fixed.score(a, b), 1.0, 1e-6);
  // The same words and options give the same file.
  EXPECT_EQ(online.to_vocabulary(build).serialize(), fixed.serialize());

  EXPECT_THROW(OnlineVocabulary(32).to_vocabulary(build), InvalidArgument);
}

}  // namespace
}  // namespace binbow
