// Damaged and hostile files: every reader rejects them with a FileError that
// names the file and the problem, and never allocates by a header's word.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "core/little_endian.h"
#include "formats/codecs.h"
#include "formats/gzip.h"
#include "support/random_tree.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::read_file;
using test::TempDir;
using test::write_file;

// Loads `bytes` saved as `name` and returns the FileError's problem; fails the
// test if the load succeeds or throws anything else.
std::string rejection(const TempDir& dir, const std::string& name,
                      const std::vector<std::uint8_t>& bytes,
                      VocabularyFormat format = VocabularyFormat::kAuto) {
  const std::string path = dir.file(name);
  write_file(path, bytes);
  try {
    load_vocabulary(path, format);
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    EXPECT_FALSE(e.problem().empty());
    return e.problem();
  } catch (const std::exception& e) {
    ADD_FAILURE() << name << ": unexpected exception " << e.what();
    return {};
  }
  ADD_FAILURE() << name << ": damaged file was accepted";
  return {};
}

std::vector<std::uint8_t> bytes_of(const std::string& text) {
  return {text.begin(), text.end()};
}

class DamagedFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937_64 rng(99);
    vocabulary_ = Vocabulary::from_tree(test::random_tree(5, 3, 32, rng));
    for (const char* name : kNames) {
      save_vocabulary(vocabulary_, dir_.file(name));
      valid_.push_back(read_file(dir_.file(name)));
    }
  }
  static constexpr const char* kNames[] = {"v.bbw",    "v.txt",   "v.bin", "v.yml",
                                           "v.yml.gz", "v.dbow3", "v.fbow"};
  TempDir dir_;
  Vocabulary vocabulary_;
  std::vector<std::vector<std::uint8_t>> valid_;
};

TEST_F(DamagedFiles, EmptyFilesAreRejected) {
  for (const char* name : kNames) {
    SCOPED_TRACE(name);
    EXPECT_NE(rejection(dir_, std::string("empty-") + name, {}).find("empty"), std::string::npos);
  }
}

TEST_F(DamagedFiles, TruncatedFilesAreRejected) {
  for (std::size_t f = 0; f < std::size(kNames); ++f) {
    const std::vector<std::uint8_t>& bytes = valid_[f];
    const std::string name = kNames[f];
    // Text formats end with a number that stays a number when cut, so they
    // are cut inside (missing nodes always leave an inner node childless or
    // a word list short); binary formats are cut anywhere.
    const bool text = name == "v.txt" || name == "v.yml";
    std::vector<std::size_t> cuts = {bytes.size() / 3, bytes.size() / 2, bytes.size() * 2 / 3};
    if (!text)
      for (const std::size_t cut : {1, 7, 8, 12, 23, 24, 64, 100}) cuts.push_back(cut);
    if (!text) cuts.push_back(bytes.size() - 1);
    for (const std::size_t cut : cuts) {
      SCOPED_TRACE(name + " cut at " + std::to_string(cut));
      rejection(dir_, "cut-" + name, {bytes.begin(), bytes.begin() + cut});
    }
  }
}

// What load_vocabulary does, from memory (files are slow to write 1000 times).
Vocabulary load_from_memory(const std::vector<std::uint8_t>& bytes, const std::string& name) {
  const VocabularyFormat format = format_for_output(name);
  if (format == VocabularyFormat::kBinbow)
    return Vocabulary::deserialize(bytes.data(), bytes.size(), name);
  if (detail::is_gzip(bytes.data(), bytes.size())) {
    const std::vector<std::uint8_t> text =
        detail::gunzip(bytes.data(), bytes.size(), name, detail::gunzip_limit(bytes.size()));
    return detail::vocabulary_from_parsed(detail::parse_dbow2_yaml(text.data(), text.size(), name),
                                          name);
  }
  return detail::vocabulary_from_parsed(
      detail::parse_vocabulary_bytes(format, bytes.data(), bytes.size(), name), name);
}

TEST_F(DamagedFiles, FlippedBytesNeverCrash) {
  std::mt19937_64 rng(3);
  for (std::size_t f = 0; f < std::size(kNames); ++f) {
    SCOPED_TRACE(kNames[f]);
    EXPECT_EQ(load_from_memory(valid_[f], kNames[f]).checksum(), vocabulary_.checksum());
    int rejected = 0;
    for (int round = 0; round < 300; ++round) {
      std::vector<std::uint8_t> bytes = valid_[f];
      const int flips = 1 + static_cast<int>(rng() % 3);
      for (int i = 0; i < flips; ++i) bytes[rng() % bytes.size()] ^= 1u << (rng() % 8);
      try {
        EXPECT_FALSE(load_from_memory(bytes, kNames[f]).empty());
      } catch (const FileError& e) {
        EXPECT_EQ(e.path(), kNames[f]);
        ++rejected;
      }
    }
    EXPECT_GT(rejected, 0);
  }
}

TEST_F(DamagedFiles, WrongMagicIsRejected) {
  for (const std::size_t f : {0u, 5u, 6u}) {  // bbw, dbow3, fbow
    SCOPED_TRACE(kNames[f]);
    std::vector<std::uint8_t> bytes = valid_[f];
    bytes[0] ^= 0x55;
    const std::string problem = rejection(dir_, std::string("magic-") + kNames[f], bytes);
    EXPECT_TRUE(problem.find("magic") != std::string::npos ||
                problem.find("signature") != std::string::npos)
        << problem;
  }
  // Nothing recognisable and no known extension.
  EXPECT_NE(rejection(dir_, "mystery.dat", bytes_of("hello\n")).find("unknown vocabulary format"),
            std::string::npos);
}

TEST_F(DamagedFiles, AbsurdHeaderValuesFailWithoutAllocating) {
  EXPECT_NE(rejection(dir_, "absurd.txt", bytes_of("4000000000 4000000000 0 0\n0 1 1 2 3 0.5\n"))
                .find("k = 4000000000"),
            std::string::npos);
  EXPECT_NE(rejection(dir_, "huge.txt", bytes_of("99999999999999999999999 1 0 0\n")).find("line 1"),
            std::string::npos);
  EXPECT_NE(rejection(dir_, "scoring.txt", bytes_of("10 6 9 0\n0 1 1 2 0.5\n")).find("scoring"),
            std::string::npos);
  EXPECT_NE(rejection(dir_, "header-only.txt", bytes_of("10 6 0 0\n")).find("no node lines"),
            std::string::npos);

  // Binary headers announcing four billion nodes in a tiny file.
  std::vector<std::uint8_t> bin = valid_[2];
  detail::store_le<std::uint32_t>(bin.data(), 4000000000u);
  EXPECT_NE(rejection(dir_, "absurd.bin", bin).find("truncated"), std::string::npos);
  std::vector<std::uint8_t> dbow3 = valid_[5];
  detail::store_le<std::uint32_t>(dbow3.data() + 9, 4000000000u);
  EXPECT_NE(rejection(dir_, "absurd.dbow3", dbow3).find("truncated"), std::string::npos);
  std::vector<std::uint8_t> fbow = valid_[6];
  detail::store_le<std::uint32_t>(fbow.data() + 8 + 56, 4000000000u);
  EXPECT_NE(rejection(dir_, "absurd.fbow", fbow).find("blocks"), std::string::npos);
  std::vector<std::uint8_t> yaml = bytes_of(
      "%YAML:1.0\n---\nvocabulary:\n   k: 4000000000\n   L: 4000000000\n   scoringType: 0\n"
      "   weightingType: 0\n   nodes:\n      - { nodeId:1, parentId:0, weight:0., "
      "descriptor:\"1 \" }\n");
  EXPECT_NE(rejection(dir_, "absurd.yml", yaml).find("k = 4000000000"), std::string::npos);
}

TEST_F(DamagedFiles, ParentsOutsideTheTreeOrInCyclesAreRejected) {
  // ORB-SLAM text: a parent must be an earlier line.
  EXPECT_NE(rejection(dir_, "parent.txt", bytes_of("2 1 0 0\n5 1 1 2 0.5\n0 1 3 4 0.5\n"))
                .find("line 2: parent id 5"),
            std::string::npos);
  EXPECT_NE(rejection(dir_, "self.txt", bytes_of("2 2 0 0\n0 0 1 2 0\n2 1 3 4 0.5\n"))
                .find("line 3: parent id 2"),
            std::string::npos);
  // Leaf flags must agree with the tree.
  EXPECT_NE(rejection(dir_, "leaf.txt", bytes_of("2 2 0 0\n0 1 1 2 0.5\n1 1 3 4 0.5\n"))
                .find("marked as a leaf but has children"),
            std::string::npos);
  EXPECT_NE(rejection(dir_, "inner.txt", bytes_of("2 2 0 0\n0 0 1 2 0\n0 1 3 4 0.5\n"))
                .find("inner node but has no children"),
            std::string::npos);
  // DBoW2 YAML: ids are explicit, so cycles are possible; they are found.
  const std::string head =
      "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 3\n   scoringType: 0\n   weightingType: 0\n"
      "   nodes:\n";
  const std::string cycle = head +
                            "      - { nodeId:1, parentId:0, weight:1., descriptor:\"1 \" }\n"
                            "      - { nodeId:2, parentId:3, weight:0., descriptor:\"2 \" }\n"
                            "      - { nodeId:3, parentId:2, weight:1., descriptor:\"3 \" }\n";
  EXPECT_NE(rejection(dir_, "cycle.yml", bytes_of(cycle)).find("not reachable"), std::string::npos);
  const std::string outside = head +
                              "      - { nodeId:1, parentId:0, weight:1., descriptor:\"1 \" }\n"
                              "      - { nodeId:2, parentId:7, weight:1., descriptor:\"2 \" }\n";
  EXPECT_NE(rejection(dir_, "outside.yml", bytes_of(outside)).find("parentId 7"),
            std::string::npos);
  const std::string twice = head +
                            "      - { nodeId:1, parentId:0, weight:1., descriptor:\"1 \" }\n"
                            "      - { nodeId:1, parentId:0, weight:1., descriptor:\"2 \" }\n";
  EXPECT_NE(rejection(dir_, "twice.yml", bytes_of(twice)).find("appears twice"), std::string::npos);
  // fbow: a block linking back to the root block.
  std::vector<std::uint8_t> fbow = valid_[6];
  const std::uint64_t child_offset = detail::load_le<std::uint64_t>(fbow.data() + 8 + 88);
  std::uint8_t* root_link = fbow.data() + 128 + child_offset;
  ASSERT_EQ(detail::load_le<std::uint32_t>(root_link) & 0x80000000u, 0u);
  detail::store_le<std::uint32_t>(root_link, 0);
  EXPECT_NE(rejection(dir_, "cycle.fbow", fbow).find("reached twice"), std::string::npos);
}

// Every format's words weigh 0 (a stop word) or more, and not all 0: the
// check is shared by all readers (here ORB-SLAM text, two words).
TEST_F(DamagedFiles, NegativeWordWeightsAreRejected) {
  EXPECT_NE(rejection(dir_, "negative.txt", bytes_of("2 1 0 0\n0 1 1 2 0.5\n0 1 3 4 -1\n"))
                .find("is negative"),
            std::string::npos);
  // All at 0 is legal but useless: read (the commands warn).
  write_file(dir_.file("zero.txt"), bytes_of("2 1 0 0\n0 1 1 2 0\n0 1 3 4 0\n"));
  EXPECT_EQ(load_vocabulary(dir_.file("zero.txt")).word_count(), 2u);
  write_file(dir_.file("one_stop_word.txt"), bytes_of("2 1 0 0\n0 1 1 2 0\n0 1 3 4 0.5\n"));
  EXPECT_EQ(load_vocabulary(dir_.file("one_stop_word.txt")).word_count(), 2u);
}

TEST_F(DamagedFiles, DescriptorsOfTheWrongLengthAreRejected) {
  EXPECT_NE(
      rejection(dir_, "short.txt", bytes_of("2 1 0 0\n0 1 1 2 0.5\n0 1 3 0.5\n")).find("line 3"),
      std::string::npos);
  EXPECT_NE(
      rejection(dir_, "byte.txt", bytes_of("2 1 0 0\n0 1 1 256 0.5\n0 1 3 4 0.5\n")).find("0..255"),
      std::string::npos);
  const std::string head =
      "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 1\n   scoringType: 0\n   weightingType: 0\n"
      "   nodes:\n      - { nodeId:1, parentId:0, weight:1., descriptor:\"";
  EXPECT_NE(rejection(dir_, "bits.yml",
                      bytes_of(head + std::string(256, '1') +
                               "\" }\n      - { nodeId:2, parentId:0, weight:1., descriptor:\"" +
                               std::string(255, '0') + "\" }\n"))
                .find("not a whole number of bytes"),
            std::string::npos);
  EXPECT_NE(rejection(dir_, "bytes.yml",
                      bytes_of(head + "1 2 3 \" }\n      - { nodeId:2, parentId:0, weight:1., "
                                      "descriptor:\"1 2 \" }\n"))
                .find("where the first had 3"),
            std::string::npos);
  EXPECT_NE(rejection(dir_, "unterminated.yml", bytes_of(head + "1 2 3 }\n")).find("unterminated"),
            std::string::npos);
}

TEST_F(DamagedFiles, CompressedDbow3IsRefusedWithAdvice) {
  std::vector<std::uint8_t> bytes = valid_[5];
  bytes[8] = 1;  // the "compressed" flag
  EXPECT_NE(rejection(dir_, "compressed.dbow3", bytes).find("unsupported: compressed DBoW3"),
            std::string::npos);
}

TEST_F(DamagedFiles, GzipBombsAreCapped) {
  EXPECT_EQ(detail::gunzip_limit(1000), std::size_t{16} << 20);
  EXPECT_EQ(detail::gunzip_limit(std::size_t{1} << 20), std::size_t{64} << 20);
  EXPECT_EQ(detail::gunzip_limit(std::size_t{1} << 40), std::size_t{4} << 30);
  const std::vector<std::uint8_t> zeros(4 << 20, 0);
  const std::vector<std::uint8_t> bomb = detail::gzip(zeros);
  EXPECT_THROW(detail::gunzip(bomb.data(), bomb.size(), "bomb.gz", zeros.size() - 1), FileError);
  EXPECT_EQ(detail::gunzip(bomb.data(), bomb.size(), "bomb.gz", zeros.size()), zeros);
  // A gzip member whose content is not YAML, and gzip garbage.
  EXPECT_FALSE(rejection(dir_, "zeros.yml.gz", bomb).empty());
  std::vector<std::uint8_t> garbage = valid_[4];
  for (std::size_t i = 20; i < garbage.size(); i += 7) garbage[i] ^= 0xFF;
  EXPECT_NE(rejection(dir_, "garbage.yml.gz", garbage).find("gzip"), std::string::npos);
}

// The cap is what a real vocabulary of that compressed size could need (16
// MiB for these): 50 MB of blanks, as one member, as 2,000 small members, or
// inside a tar archive, stop there.
TEST_F(DamagedFiles, GzipExpansionIsCappedWhateverTheContainer) {
  const std::string cap = "expands beyond " + std::to_string(16 << 20) + " bytes";
  const std::vector<std::uint8_t> blanks(50 << 20, ' ');
  const std::vector<std::uint8_t> one_member = detail::gzip(blanks);
  ASSERT_LT(one_member.size(), 100u << 10);
  EXPECT_NE(rejection(dir_, "blanks.yml.gz", one_member).find(cap), std::string::npos);

  const std::vector<std::uint8_t> member = detail::gzip(std::vector<std::uint8_t>(25 << 10, ' '));
  std::vector<std::uint8_t> members;
  for (int i = 0; i < 2000; ++i) members.insert(members.end(), member.begin(), member.end());
  EXPECT_NE(rejection(dir_, "members.yml.gz", members).find(cap), std::string::npos);

  std::vector<std::uint8_t> tar(512 + blanks.size(), ' ');
  std::fill_n(tar.begin(), 512, 0);
  std::memcpy(tar.data(), "ORBvoc.txt", 10);
  std::memcpy(tar.data() + 257, "ustar", 5);
  std::memcpy(tar.data() + 124, "00310000000", 11);  // 50 MiB in octal
  tar[156] = '0';
  EXPECT_NE(rejection(dir_, "blanks.txt.tar.gz", detail::gzip(tar)).find(cap), std::string::npos);

  // Concatenated members of a real file still load: the cap is on their total.
  const std::vector<std::uint8_t> yaml = valid_[3];
  const std::size_t half = yaml.size() / 2;
  std::vector<std::uint8_t> two = detail::gzip({yaml.begin(), yaml.begin() + half});
  const std::vector<std::uint8_t> second = detail::gzip({yaml.begin() + half, yaml.end()});
  two.insert(two.end(), second.begin(), second.end());
  write_file(dir_.file("two.yml.gz"), two);
  EXPECT_EQ(load_vocabulary(dir_.file("two.yml.gz")).checksum(), vocabulary_.checksum());
}

// The trailer's size field is never trusted: a forged one is found false
// (zlib checks it), and a cut file fails as truncated.
TEST_F(DamagedFiles, GzipTrailerIsNotTrusted) {
  std::vector<std::uint8_t> forged = valid_[4];
  detail::store_le<std::uint32_t>(forged.data() + forged.size() - 4, 0xFFFFFFFFu);
  EXPECT_NE(rejection(dir_, "forged.yml.gz", forged).find("gzip data is corrupt"),
            std::string::npos);
  const std::vector<std::uint8_t> cut(valid_[4].begin(), valid_[4].end() - 1);
  EXPECT_NE(rejection(dir_, "cut.yml.gz", cut).find("truncated"), std::string::npos);
}

TEST_F(DamagedFiles, MalformedTarArchivesAreRejected) {
  std::vector<std::uint8_t> tar(2048, 0);
  std::memcpy(tar.data(), "ORBvoc.txt", 10);
  std::memcpy(tar.data() + 257, "ustar", 5);
  tar[156] = '0';
  std::memcpy(tar.data() + 124, "9z9", 3);
  EXPECT_NE(rejection(dir_, "badsize.txt.tar.gz", detail::gzip(tar)).find("bad size field"),
            std::string::npos);
  std::memcpy(tar.data() + 124, "77777777777", 11);
  EXPECT_NE(rejection(dir_, "huge.txt.tar.gz", detail::gzip(tar)).find("truncated tar"),
            std::string::npos);
  tar[156] = '5';  // only a directory
  std::memcpy(tar.data() + 124, "00000000000", 11);
  EXPECT_NE(rejection(dir_, "dir.txt.tar.gz", detail::gzip(tar)).find("no regular file"),
            std::string::npos);
}

TEST_F(DamagedFiles, ParsersRejectEveryPrefixOfSmallFiles) {
  // Exhaustive on a tiny vocabulary: no prefix may crash a parser.
  VocabularyTree tree;
  tree.code_size = 2;
  tree.branching = 2;
  tree.levels = 2;
  tree.parent = {0, 0, 0, 1, 1};
  tree.descriptors = {0, 0, 1, 2, 3, 4, 5, 6, 7, 8};
  tree.weights = {0, 0, 1.5f, 2.5f, 3.5f};
  const VocabularyTree canonical = Vocabulary::from_tree(tree).to_tree();
  const std::vector<std::vector<std::uint8_t>> files = {
      detail::format_orbslam_text(canonical), detail::format_orbslam_binary(canonical),
      detail::format_dbow2_yaml(canonical, detail::DescriptorText::kBits),
      detail::format_dbow3_binary(canonical), detail::format_fbow(canonical)};
  const VocabularyFormat formats[] = {
      VocabularyFormat::kOrbSlamText, VocabularyFormat::kOrbSlamBinary,
      VocabularyFormat::kDbow2Yaml, VocabularyFormat::kDbow3, VocabularyFormat::kFbow};
  for (std::size_t f = 0; f < files.size(); ++f) {
    for (std::size_t cut = 0; cut < files[f].size(); ++cut) {
      try {
        detail::vocabulary_from_parsed(
            detail::parse_vocabulary_bytes(formats[f], files[f].data(), cut, "prefix"), "prefix");
      } catch (const FileError&) {
      }
    }
    EXPECT_NO_THROW(detail::vocabulary_from_parsed(
        detail::parse_vocabulary_bytes(formats[f], files[f].data(), files[f].size(), "whole"),
        "whole"));
  }
}

}  // namespace
}  // namespace binbow
