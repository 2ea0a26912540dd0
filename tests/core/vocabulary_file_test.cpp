#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <limits>
#include <random>

#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "core/crc32c.h"
#include "core/little_endian.h"
#include "core/reference_tree.h"
#include "support/test_support.h"

namespace binbow {
namespace {

void expect_file_error(const std::string& path, const std::string& fragment);

Vocabulary sample_vocabulary(std::uint64_t seed = 9) {
  std::mt19937_64 rng(seed);
  return Vocabulary::from_tree(test::random_tree(rng, 32, 5, 3));
}

TEST(VocabularyFile, SaveLoadIsBitExactAndBehavesTheSame) {
  test::TempDir dir;
  const Vocabulary v = sample_vocabulary();
  v.save(dir.file("v.bbw"));
  const Vocabulary loaded = Vocabulary::load(dir.file("v.bbw"));
  EXPECT_EQ(test::read_file(dir.file("v.bbw")), v.serialize());
  EXPECT_EQ(loaded.serialize(), v.serialize());
  EXPECT_EQ(loaded.checksum(), v.checksum());
  std::mt19937_64 rng(1);
  const auto d = test::random_descriptors(100, 32, rng);
  BowVector a, b;
  v.transform(d, a);
  loaded.transform(d, b);
  EXPECT_EQ(a, b);
  // Scoring overrides are saved.
  v.with_scoring(Scoring::kBhattacharyya).save(dir.file("s.bbw"));
  EXPECT_EQ(Vocabulary::load(dir.file("s.bbw")).scoring(), Scoring::kBhattacharyya);
}

TEST(VocabularyFile, RecordsTheDescriptorNameOutsideTheContentChecksum) {
  test::TempDir dir;
  std::mt19937_64 rng(9);
  VocabularyTree tree = test::random_tree(rng, 32, 5, 3);
  const Vocabulary unnamed = Vocabulary::from_tree(tree);
  EXPECT_EQ(unnamed.descriptor(), "");
  tree.descriptor = "brief";
  const Vocabulary named = Vocabulary::from_tree(tree);
  named.save(dir.file("v.bbw"));
  const Vocabulary loaded = Vocabulary::load(dir.file("v.bbw"));
  EXPECT_EQ(loaded.descriptor(), "brief");
  EXPECT_EQ(loaded.to_tree().descriptor, "brief");
  // The same words whatever the label: databases stay compatible.
  EXPECT_EQ(loaded.checksum(), unnamed.checksum());
  for (const char* bad : {"BRIEF", "orb 2", "toolongname", "é"}) {
    tree.descriptor = bad;
    EXPECT_THROW(Vocabulary::from_tree(tree), InvalidArgument) << bad;
  }
  // A damaged name field with a valid header CRC is rejected.
  std::vector<std::uint8_t> bytes = named.serialize();
  bytes[52 + 6] = 'x';  // after the name's terminating zero
  detail::store_le<std::uint32_t>(bytes.data() + 60, detail::crc32c(bytes.data(), 60));
  test::write_file(dir.file("bad.bbw"), bytes);
  expect_file_error(dir.file("bad.bbw"), "descriptor name");
}

TEST(VocabularyFile, SaveIsAtomicAndLeavesNoTemporaryFiles) {
  test::TempDir dir;
  const Vocabulary v = sample_vocabulary();
  v.save(dir.file("v.bbw"));
  v.save(dir.file("v.bbw"));
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) (void)e, ++files;
  EXPECT_EQ(files, 1u);
  EXPECT_THROW(v.save(dir.file("v.bbw/inside.bbw")), FileError);  // a file on the way
  v.save(dir.file("missing-dir/v.bbw"));                          // made
  EXPECT_EQ(Vocabulary::load(dir.file("missing-dir/v.bbw")).checksum(), v.checksum());
}

void expect_file_error(const std::string& path, const std::string& fragment) {
  try {
    Vocabulary::load(path);
    ADD_FAILURE() << "loaded a damaged file, expected: " << fragment;
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(VocabularyFile, RejectsDamagedFilesWithClearErrors) {
  test::TempDir dir;
  const std::vector<std::uint8_t> good = sample_vocabulary().serialize();
  expect_file_error(dir.file("missing.bbw"), "cannot open");
  test::write_file(dir.file("empty.bbw"), {});
  expect_file_error(dir.file("empty.bbw"), "empty");
  expect_file_error(dir.path(), "directory");

  for (std::size_t cut :
       {std::size_t{10}, std::size_t{64}, std::size_t{100}, good.size() / 2, good.size() - 1}) {
    test::write_file(dir.file("cut.bbw"), {good.begin(), good.begin() + static_cast<long>(cut)});
    EXPECT_THROW(Vocabulary::load(dir.file("cut.bbw")), FileError) << "truncated at " << cut;
  }
  auto bad = good;
  bad[0] = 'X';
  test::write_file(dir.file("magic.bbw"), bad);
  expect_file_error(dir.file("magic.bbw"), "wrong magic");
  bad = good;
  bad[8] = 9;
  test::write_file(dir.file("version.bbw"), bad);
  expect_file_error(dir.file("version.bbw"), "version 9");
  bad = good;
  bad[good.size() - 70] ^= 0x40;
  test::write_file(dir.file("flip.bbw"), bad);
  expect_file_error(dir.file("flip.bbw"), "checksum mismatch");
}

TEST(VocabularyFile, EveryFlippedByteIsRejected) {
  // Checksums cover the header, the table and the sections; padding must be zero.
  const Vocabulary v = sample_vocabulary(3);
  const std::vector<std::uint8_t> good = v.serialize();
  for (std::size_t i = 0; i < good.size(); ++i) {
    auto bad = good;
    bad[i] ^= 0x01;
    EXPECT_THROW(Vocabulary::deserialize(bad.data(), bad.size(), "flipped"), FileError)
        << "byte " << i;
  }
}

// Offset of section `index` (0-based) from the section table.
std::size_t section_offset(const std::vector<std::uint8_t>& bytes, std::size_t index) {
  return detail::load_le<std::uint64_t>(bytes.data() + 64 + index * 24 + 8);
}

void recompute_section_crc(std::vector<std::uint8_t>& bytes, std::size_t index) {
  std::uint8_t* entry = bytes.data() + 64 + index * 24;
  const auto offset = detail::load_le<std::uint64_t>(entry + 8);
  const auto length = detail::load_le<std::uint64_t>(entry + 16);
  detail::store_le<std::uint32_t>(entry + 4, detail::crc32c(bytes.data() + offset, length));
  detail::store_le<std::uint32_t>(bytes.data() + 64 + 4 * 24,
                                  detail::crc32c(bytes.data() + 64, 4 * 24));
}

TEST(VocabularyFile, NonzeroPaddingIsRejectedEvenWithoutChecksums) {
  test::TempDir dir;
  std::vector<std::uint8_t> bytes = sample_vocabulary().serialize();
  const std::size_t weights = section_offset(bytes, 3);
  ASSERT_EQ(bytes[weights - 1], 0);  // the child counts never fill their last 64 bytes here
  bytes[weights - 1] = 0x20;
  test::write_file(dir.file("padding.bbw"), bytes);
  expect_file_error(dir.file("padding.bbw"), "nonzero padding before section 'word weights'");
  LoadOptions no_crc;
  no_crc.verify_checksums = false;
  EXPECT_THROW(Vocabulary::deserialize(bytes.data(), bytes.size(), "padding", no_crc), FileError);
}

TEST(VocabularyFile, NonFiniteWeightsAreRejectedWithValidChecksums) {
  test::TempDir dir;
  const std::vector<std::uint8_t> good = sample_vocabulary().serialize();
  for (const float weight :
       {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    std::vector<std::uint8_t> bytes = good;
    detail::store_le<float>(bytes.data() + section_offset(bytes, 3) + 4, weight);
    recompute_section_crc(bytes, 3);
    test::write_file(dir.file("weights.bbw"), bytes);
    expect_file_error(dir.file("weights.bbw"), "the weight of word 1 is not a finite number");
  }
  // Nor can a tree with one be made into a vocabulary (nor then saved).
  const Vocabulary v = sample_vocabulary();
  VocabularyTree broken = v.to_tree();
  for (std::size_t node = broken.node_count(); node-- > 1;)
    if (v.is_leaf(static_cast<NodeId>(node))) {
      broken.weights[node] = std::numeric_limits<float>::quiet_NaN();
      break;
    }
  EXPECT_THROW(Vocabulary::from_tree(broken), InvalidArgument);
}

TEST(VocabularyFile, WithDescriptorRecordsAnExtractorAndKeepsTheWords) {
  test::TempDir dir;
  const Vocabulary unnamed = sample_vocabulary();
  const Vocabulary named = unnamed.with_scoring(Scoring::kL2).with_descriptor("brief");
  EXPECT_EQ(named.descriptor(), "brief");
  EXPECT_EQ(named.scoring(), Scoring::kL2);
  EXPECT_EQ(named.checksum(), unnamed.with_scoring(Scoring::kL2).checksum());
  named.save(dir.file("named.bbw"));
  EXPECT_EQ(Vocabulary::load(dir.file("named.bbw")).descriptor(), "brief");
  EXPECT_EQ(named.with_descriptor("orb").descriptor(), "orb");
  EXPECT_EQ(named.with_descriptor("").descriptor(), "");
  EXPECT_THROW(unnamed.with_descriptor("BRIEF"), InvalidArgument);
  EXPECT_THROW(unnamed.with_descriptor("toolongname"), InvalidArgument);
  EXPECT_THROW(Vocabulary().with_descriptor("orb"), InvalidArgument);
}

TEST(VocabularyFile, StructuralChecksCatchForgedTreesEvenWithoutChecksums) {
  // Forge a links section pointing backwards (a cycle) and skip checksum checks:
  // the structural validation must still refuse it.
  const Vocabulary v = sample_vocabulary(4);
  auto bytes = v.serialize();
  std::size_t links_offset = 0;
  std::memcpy(&links_offset, bytes.data() + 64 + 24 + 8, 8);
  const std::uint32_t back = 0;
  std::memcpy(bytes.data() + links_offset + 4, &back, 4);  // node 1 → root's block
  LoadOptions no_crc;
  no_crc.verify_checksums = false;
  EXPECT_THROW(Vocabulary::deserialize(bytes.data(), bytes.size(), "forged", no_crc), FileError);
}

// Words weigh 0 (a stop word) or more under every weighting: a negative
// weight means nothing, and a vocabulary of stop words only turns every
// image into an empty BoW vector (then no loop is ever found).
// Negative weights mean nothing in any weighting: refused. All words at 0 is
// legal but useless: read (databases and states saved with one still load);
// the commands warn.
TEST(VocabularyFile, NegativeWeightsAreRejectedAllZeroAreRead) {
  test::TempDir dir;
  for (const Weighting weighting :
       {Weighting::kTfIdf, Weighting::kIdf, Weighting::kTf, Weighting::kBinary}) {
    SCOPED_TRACE(to_string(weighting));
    std::vector<std::uint8_t> good = sample_vocabulary().serialize();
    good[28] = static_cast<std::uint8_t>(weighting);
    detail::store_le<std::uint32_t>(good.data() + 60, detail::crc32c(good.data(), 60));
    ASSERT_NO_THROW(Vocabulary::deserialize(good.data(), good.size(), "good"));
    const std::size_t words =
        Vocabulary::deserialize(good.data(), good.size(), "good").word_count();
    for (const float weight : {-1.0f, 0.0f}) {
      std::vector<std::uint8_t> bytes = good;
      for (std::size_t word = 0; word < words; ++word)
        detail::store_le<float>(bytes.data() + section_offset(bytes, 3) + 4 * word, weight);
      recompute_section_crc(bytes, 3);
      test::write_file(dir.file("weights.bbw"), bytes);
      if (weight < 0) {
        expect_file_error(dir.file("weights.bbw"), "the weight of word 0 is negative");
      } else {
        EXPECT_EQ(Vocabulary::load(dir.file("weights.bbw")).word_weight(0), 0.0f);
      }
    }
    // One stop word among others is fine.
    std::vector<std::uint8_t> bytes = good;
    detail::store_le<float>(bytes.data() + section_offset(bytes, 3), 0.0f);
    recompute_section_crc(bytes, 3);
    EXPECT_NO_THROW(Vocabulary::deserialize(bytes.data(), bytes.size(), "one stop word"));
  }
}

}  // namespace
}  // namespace binbow
