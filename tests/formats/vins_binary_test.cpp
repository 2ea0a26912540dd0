// The VINS-Mono/VINS-Fusion binary vocabulary (brief_k10L6.bin layout): round
// trips, the BRIEF bit order against hand-made files and FBrief's bit strings,
// detection by exact size next to ORB-SLAM's binary format, and damaged files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "core/little_endian.h"
#include "formats/codecs.h"
#include "formats/gzip.h"
#include "formats/loader.h"
#include "support/random_tree.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::read_file;
using test::shared_data;
using test::TempDir;
using test::write_file;

// A VINS file written field by field, as VINSLoop::Vocabulary::serialize does.
struct VinsNode {
  std::int32_t id, parent;
  double weight;
  std::uint64_t descriptor[4];
};
struct VinsWord {
  std::int32_t node, word;
};
std::vector<std::uint8_t> vins_file(std::int32_t k, std::int32_t levels,
                                    const std::vector<VinsNode>& nodes,
                                    const std::vector<VinsWord>& words, std::int32_t scoring = 0,
                                    std::int32_t weighting = 0) {
  std::vector<std::uint8_t> out;
  for (const std::int32_t value :
       {k, levels, scoring, weighting, static_cast<std::int32_t>(nodes.size()),
        static_cast<std::int32_t>(words.size())})
    detail::put_le(out, value);
  for (const VinsNode& node : nodes) {
    detail::put_le(out, node.id);
    detail::put_le(out, node.parent);
    detail::put_le(out, node.weight);
    for (const std::uint64_t block : node.descriptor) detail::put_le(out, block);
  }
  for (const VinsWord& word : words) {
    detail::put_le(out, word.node);
    detail::put_le(out, word.word);
  }
  return out;
}

// Root with three leaves (k = 3, L = 1) and a second level under node 1.
std::vector<VinsNode> small_nodes() {
  return {{1, 0, 0.0, {1, 2, 3, 4}},
          {2, 0, 0.5, {5, 6, 7, 8}},
          {3, 0, 1.5, {9, 10, 11, 12}},
          {4, 1, 2.5, {13, 14, 15, 16}},
          {5, 1, 3.5, {17, 18, 19, 20}}};
}
std::vector<VinsWord> small_words() {
  return {{2, 0}, {3, 1}, {4, 2}, {5, 3}};
}

Vocabulary random_vocabulary(std::uint32_t k, std::uint32_t levels, std::size_t code_size,
                             std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  VocabularyTree tree = test::random_tree(k, levels, code_size, rng);
  tree.weighting = Weighting::kIdf;
  tree.scoring = Scoring::kChiSquare;
  return Vocabulary::from_tree(tree);
}

void expect_same_vocabulary(const Vocabulary& expected, const Vocabulary& actual) {
  const VocabularyTree a = expected.to_tree(), b = actual.to_tree();
  EXPECT_EQ(a.code_size, b.code_size);
  EXPECT_EQ(a.branching, b.branching);
  EXPECT_EQ(a.levels, b.levels);
  EXPECT_EQ(a.weighting, b.weighting);
  EXPECT_EQ(a.scoring, b.scoring);
  EXPECT_EQ(a.parent, b.parent);
  EXPECT_EQ(a.descriptors, b.descriptors);
  EXPECT_EQ(a.weights, b.weights);
  EXPECT_EQ(expected.word_nodes(), actual.word_nodes());
  EXPECT_EQ(expected.checksum(), actual.checksum());
}

// Loads `bytes` saved as `name`; returns the FileError's problem after
// checking it names the file, fails the test on success or any other error.
std::string rejection(const TempDir& dir, const std::string& name,
                      const std::vector<std::uint8_t>& bytes,
                      VocabularyFormat format = VocabularyFormat::kVinsBinary) {
  const std::string path = dir.file(name);
  write_file(path, bytes);
  try {
    load_vocabulary(path, format);
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    return e.problem();
  } catch (const std::exception& e) {
    ADD_FAILURE() << name << ": unexpected exception " << e.what();
    return {};
  }
  ADD_FAILURE() << name << ": damaged file was accepted";
  return {};
}

#define EXPECT_REJECTED(name, bytes, text)                             \
  EXPECT_NE(rejection(dir, name, bytes).find(text), std::string::npos) \
      << "expected '" << (text) << "' in the problem"

TEST(VinsBinary, NamesAndExtensions) {
  EXPECT_STREQ(to_string(VocabularyFormat::kVinsBinary), "vins");
  EXPECT_EQ(parse_vocabulary_format("vins"), VocabularyFormat::kVinsBinary);
  EXPECT_EQ(parse_vocabulary_format("VINS"), VocabularyFormat::kVinsBinary);
  EXPECT_EQ(format_for_output("a/brief_k10L6.vins.bin"), VocabularyFormat::kVinsBinary);
  EXPECT_EQ(format_for_output("a/brief_k10L6.VINS.BIN.gz"), VocabularyFormat::kVinsBinary);
  EXPECT_EQ(format_for_output("a/ORBvoc.bin"), VocabularyFormat::kOrbSlamBinary);
}

TEST(VinsBinary, RandomTreeRoundTripKeepsTreeWordsAndBytes) {
  TempDir dir;
  const Vocabulary vocabulary = random_vocabulary(6, 4, 32, 17);
  save_vocabulary(vocabulary, dir.file("v.data"), VocabularyFormat::kVinsBinary);
  const std::vector<std::uint8_t> bytes = read_file(dir.file("v.data"));
  EXPECT_EQ(bytes.size(),
            24 + 48 * (vocabulary.node_count() - 1) + 8 * std::size_t{vocabulary.word_count()});
  const detail::LoadedVocabulary loaded =
      detail::load_vocabulary_with_details(dir.file("v.data"), VocabularyFormat::kAuto);
  EXPECT_EQ(loaded.format, VocabularyFormat::kVinsBinary);
  EXPECT_TRUE(loaded.word_ids_match);
  // VINS computes BRIEF descriptors: its vocabularies are BRIEF's, without a warning.
  EXPECT_EQ(loaded.vocabulary.descriptor(), "brief");
  EXPECT_TRUE(loaded.descriptor_warning.empty()) << loaded.descriptor_warning;
  expect_same_vocabulary(vocabulary, loaded.vocabulary);
  // bbw -> vins -> bbw -> vins: the same bytes both times.
  save_vocabulary(loaded.vocabulary, dir.file("back.bbw"));
  save_vocabulary(load_vocabulary(dir.file("back.bbw")), dir.file("again.vins.bin"));
  EXPECT_EQ(read_file(dir.file("again.vins.bin")), bytes);
  // Compressed too.
  save_vocabulary(vocabulary, dir.file("v.vins.bin.gz"));
  const detail::LoadedVocabulary gz =
      detail::load_vocabulary_with_details(dir.file("v.vins.bin.gz"), VocabularyFormat::kAuto);
  EXPECT_TRUE(gz.compressed);
  EXPECT_EQ(gz.format, VocabularyFormat::kVinsBinary);
  EXPECT_EQ(gz.vocabulary.checksum(), vocabulary.checksum());
  EXPECT_EQ(gz.vocabulary.descriptor(), "brief");
}

// A VINS file holds no name: an ORB vocabulary written in its layout reads
// back as ORB's when told so.
TEST(VinsBinary, ReadsAsBriefUnlessToldOtherwise) {
  TempDir dir;
  const Vocabulary orb = random_vocabulary(6, 4, 32, 17).with_descriptor("orb");
  save_vocabulary(orb, dir.file("v.vins.bin"));
  std::vector<std::string> warnings;
  set_warning_handler([&](const std::string& message) { warnings.push_back(message); });
  const Vocabulary assumed = load_vocabulary(dir.file("v.vins.bin"));
  const Vocabulary told = load_vocabulary(dir.file("v.vins.bin"), VocabularyFormat::kAuto, "orb");
  set_warning_handler(nullptr);
  EXPECT_EQ(assumed.descriptor(), "brief");
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  EXPECT_EQ(told.descriptor(), "orb");
  told.save(dir.file("back.bbw"));
  orb.save(dir.file("orb.bbw"));
  EXPECT_EQ(read_file(dir.file("back.bbw")), read_file(dir.file("orb.bbw")));
}

// VINS's header holds DBoW2's enum values, as the other formats' headers.
TEST(VinsBinary, HeaderHoldsDbow2Codes) {
  TempDir dir;
  const Vocabulary vocabulary = random_vocabulary(5, 3, 32, 3);  // idf, chi-square
  save_vocabulary(vocabulary, dir.file("v.vins.bin"));
  const std::vector<std::uint8_t> bytes = read_file(dir.file("v.vins.bin"));
  EXPECT_EQ(detail::load_le<std::int32_t>(bytes.data()), 5);
  EXPECT_EQ(detail::load_le<std::int32_t>(bytes.data() + 4), 3);
  EXPECT_EQ(detail::load_le<std::int32_t>(bytes.data() + 8), 2);   // DBoW2 CHI_SQUARE
  EXPECT_EQ(detail::load_le<std::int32_t>(bytes.data() + 12), 2);  // DBoW2 IDF
}

// The hand-made file's node i (a leaf under the root) has only BRIEF test
// t_i set, as VINS stores it: bit t % 64 of descriptor[t / 64]. binbow's BRIEF
// extractor puts test t at bit t % 8 of byte t / 8; a descriptor with test
// t_i set must reach node i's word.
TEST(VinsBinary, BriefTestBitsReachTheirWords) {
  TempDir dir;
  const std::uint32_t tests[] = {0, 5, 63, 64, 70, 130, 200, 255};
  std::vector<VinsNode> nodes;
  std::vector<VinsWord> words;
  for (std::int32_t i = 0; i < 8; ++i) {
    VinsNode node{i + 1, 0, 1.0 + i, {0, 0, 0, 0}};
    node.descriptor[tests[i] / 64] = std::uint64_t{1} << (tests[i] % 64);
    nodes.push_back(node);
    words.push_back({i + 1, i});
  }
  write_file(dir.file("bits.data"), vins_file(8, 1, nodes, words));
  ASSERT_EQ(detect_vocabulary_format(dir.file("bits.data")), VocabularyFormat::kVinsBinary);
  const Vocabulary vocabulary = load_vocabulary(dir.file("bits.data"));
  ASSERT_EQ(vocabulary.word_count(), 8u);
  for (std::uint32_t i = 0; i < 8; ++i) {
    SCOPED_TRACE("BRIEF test " + std::to_string(tests[i]));
    std::uint8_t descriptor[32] = {};
    descriptor[tests[i] / 8] = static_cast<std::uint8_t>(1u << (tests[i] % 8));
    EXPECT_EQ(vocabulary.quantize(descriptor), i);
    EXPECT_EQ(std::memcmp(vocabulary.node_descriptor(vocabulary.word_nodes()[i]), descriptor, 32),
              0);
  }
  // Written back, the bytes are the hand-made ones.
  save_vocabulary(vocabulary, dir.file("again.vins.bin"));
  EXPECT_EQ(read_file(dir.file("again.vins.bin")), read_file(dir.file("bits.data")));
}

// A tiny DBoW2 YAML file with FBrief's bit strings (character k = test
// 255 - k) and the VINS file of the same tree give the same vocabulary.
TEST(VinsBinary, AgreesWithFbriefBitStrings) {
  TempDir dir;
  std::string yaml =
      "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 1\n   scoringType: 0\n   weightingType: 0\n"
      "   nodes:\n";
  std::vector<VinsNode> nodes;
  for (std::int32_t id = 1; id <= 2; ++id) {
    VinsNode node{id, 0, 0.25 * id, {0, 0, 0, 0}};
    std::string bits(256, '0');
    for (const std::uint32_t test : {id * 3u, 64u + id, 191u, 250u + id}) {
      bits[255 - test] = '1';
      node.descriptor[test / 64] |= std::uint64_t{1} << (test % 64);
    }
    yaml += "      - { nodeId:" + std::to_string(id) +
            ", parentId:0, weight:" + std::to_string(0.25 * id) + ", descriptor:\"" + bits +
            "\" }\n";
    nodes.push_back(node);
  }
  yaml += "   words:\n      - { wordId:0, nodeId:1 }\n      - { wordId:1, nodeId:2 }\n";
  write_file(dir.file("v.yml"), std::vector<std::uint8_t>(yaml.begin(), yaml.end()));
  write_file(dir.file("v.vins.bin"), vins_file(2, 1, nodes, {{1, 0}, {2, 1}}));
  EXPECT_EQ(load_vocabulary(dir.file("v.vins.bin")).checksum(),
            load_vocabulary(dir.file("v.yml")).checksum());
}

// brief_lite.voc.gz, a real VINS-family BRIEF vocabulary in DBoW2 YAML: what
// binbow writes as VINS binary lists the YAML's nodes (ids, parents, FBrief
// bit strings as VINS's 64-bit blocks) and words in the YAML's order, and
// reads back as the same vocabulary.
TEST(VinsBinary, RealBriefLiteVocabularyConvertsBothWays) {
  const std::string path = shared_data("vins-lite-brief-vocab/brief_lite.voc.gz");
  const Vocabulary vocabulary = load_vocabulary(path, VocabularyFormat::kAuto, "brief");
  ASSERT_EQ(vocabulary.node_count(), 31233u);
  TempDir dir;
  save_vocabulary(vocabulary, dir.file("brief.bbw"));
  const Vocabulary bbw = load_vocabulary(dir.file("brief.bbw"));
  save_vocabulary(bbw, dir.file("brief_k10L6.bin"), VocabularyFormat::kVinsBinary);
  const std::vector<std::uint8_t> vins = read_file(dir.file("brief_k10L6.bin"));
  ASSERT_EQ(vins.size(), 24u + 48u * 31232u + 8u * 24830u);
  ASSERT_EQ(detect_vocabulary_format(dir.file("brief_k10L6.bin")), VocabularyFormat::kVinsBinary);
  EXPECT_EQ(detail::load_le<std::int32_t>(vins.data()), 10);
  EXPECT_EQ(detail::load_le<std::int32_t>(vins.data() + 4), 6);

  const std::vector<std::uint8_t> gz = read_file(path);
  const std::vector<std::uint8_t> text_bytes =
      detail::gunzip(gz.data(), gz.size(), path, detail::gunzip_limit(gz.size()));
  const std::string text(text_bytes.begin(), text_bytes.end());
  // The YAML lists nodes parent by parent (DBoW2's save order); VINS's
  // saveBin writes them by id.
  std::size_t entries = 0, mismatches = 0;
  for (std::size_t at = text.find("{ nodeId:"); at != std::string::npos;
       at = text.find("{ nodeId:", at + 1), ++entries) {
    const long id = std::strtol(text.c_str() + at + 9, nullptr, 10);
    ASSERT_GE(id, 1);
    ASSERT_LE(id, 31232);
    const std::uint8_t* r = vins.data() + 24 + 48 * (id - 1);
    const long parent = std::strtol(text.c_str() + text.find("parentId:", at) + 9, nullptr, 10);
    const double weight = std::strtod(text.c_str() + text.find("weight:", at) + 7, nullptr);
    const std::size_t quote = text.find("descriptor:\"", at) + 12;
    EXPECT_EQ(detail::load_le<std::int32_t>(r), id);
    EXPECT_EQ(detail::load_le<std::int32_t>(r + 4), parent);
    EXPECT_NEAR(detail::load_le<double>(r + 8), weight, 1e-6 * (1 + std::fabs(weight)));
    for (std::size_t k = 0; k < 256; ++k) {
      const std::size_t test = 255 - k;
      const bool set =
          (detail::load_le<std::uint64_t>(r + 16 + 8 * (test / 64)) >> (test % 64)) & 1;
      if (set != (text[quote + k] == '1')) ++mismatches;
    }
  }
  EXPECT_EQ(entries, 31232u);
  EXPECT_EQ(mismatches, 0u);
  std::size_t word = 0;
  for (std::size_t at = text.find("{ wordId:"); at != std::string::npos;
       at = text.find("{ wordId:", at + 1), ++word) {
    ASSERT_LT(word, 24830u);
    const std::uint8_t* w = vins.data() + 24 + 48 * 31232 + 8 * word;
    EXPECT_EQ(detail::load_le<std::int32_t>(w + 4),
              std::strtol(text.c_str() + at + 9, nullptr, 10));
    EXPECT_EQ(detail::load_le<std::int32_t>(w),
              std::strtol(text.c_str() + text.find("nodeId:", at) + 7, nullptr, 10));
  }
  EXPECT_EQ(word, 24830u);

  const Vocabulary back = load_vocabulary(dir.file("brief_k10L6.bin"));
  expect_same_vocabulary(bbw, back);
  save_vocabulary(back, dir.file("back.bbw"));
  EXPECT_EQ(read_file(dir.file("back.bbw")), read_file(dir.file("brief.bbw")));
}

// Neither format has a magic number: each is told by its header predicting
// the exact file size, whatever the file is called.
TEST(VinsBinary, DetectedByExactSizeNextToOrbSlamBinary) {
  TempDir dir;
  const Vocabulary vocabulary = random_vocabulary(4, 3, 32, 8);
  save_vocabulary(vocabulary, dir.file("orb.bin"));
  save_vocabulary(vocabulary, dir.file("vins.bin"), VocabularyFormat::kVinsBinary);
  EXPECT_EQ(detect_vocabulary_format(dir.file("orb.bin")), VocabularyFormat::kOrbSlamBinary);
  EXPECT_EQ(detect_vocabulary_format(dir.file("vins.bin")), VocabularyFormat::kVinsBinary);
  EXPECT_EQ(load_vocabulary(dir.file("vins.bin")).checksum(), vocabulary.checksum());
  EXPECT_EQ(load_vocabulary(dir.file("orb.bin")).checksum(), vocabulary.checksum());
  write_file(dir.file("orb.vins.bin"), read_file(dir.file("orb.bin")));
  EXPECT_EQ(detect_vocabulary_format(dir.file("orb.vins.bin")), VocabularyFormat::kOrbSlamBinary);

  // One byte more or less and the size no longer matches: a .data file is
  // then unknown, a .bin file falls back to ORB-SLAM binary by its name.
  std::vector<std::uint8_t> longer = read_file(dir.file("vins.bin"));
  longer.push_back(0);
  write_file(dir.file("longer.data"), longer);
  EXPECT_THROW(detect_vocabulary_format(dir.file("longer.data")), FileError);
  write_file(dir.file("longer.bin"), longer);
  EXPECT_EQ(detect_vocabulary_format(dir.file("longer.bin")), VocabularyFormat::kOrbSlamBinary);
  write_file(dir.file("longer.vins.bin"), longer);
  EXPECT_EQ(detect_vocabulary_format(dir.file("longer.vins.bin")), VocabularyFormat::kVinsBinary);
  EXPECT_THROW(load_vocabulary(dir.file("longer.vins.bin")), FileError);

  // Inside a plain .gz the size shows only once decompressed: loading finds it.
  save_vocabulary(vocabulary, dir.file("v.bin.gz"), VocabularyFormat::kVinsBinary);
  const detail::LoadedVocabulary gz =
      detail::load_vocabulary_with_details(dir.file("v.bin.gz"), VocabularyFormat::kAuto);
  EXPECT_EQ(gz.format, VocabularyFormat::kVinsBinary);
  EXPECT_EQ(gz.vocabulary.checksum(), vocabulary.checksum());
}

// No file of another format in the repository and shared data is taken for
// a VINS file.
TEST(VinsBinary, NoOtherFormatsFileIsDetectedAsVins) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(test::source_path("fuzz/corpus")))
    if (entry.is_regular_file() && entry.path().parent_path().filename() != "vins_binary")
      files.push_back(entry.path());
  for (const char* folder : {"data", "tests"})
    for (const auto& entry :
         std::filesystem::recursive_directory_iterator(test::source_path(folder)))
      if (entry.is_regular_file()) files.push_back(entry.path());
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(shared_data("vins-lite-brief-vocab")))
    if (entry.is_regular_file()) files.push_back(entry.path());
  ASSERT_GT(files.size(), 100u);
  std::size_t detected = 0;
  for (const auto& file : files) {
    try {
      if (detect_vocabulary_format(file.string()) == VocabularyFormat::kVinsBinary) {
        ADD_FAILURE() << file << " is detected as a VINS vocabulary";
      }
      ++detected;
    } catch (const FileError&) {
    }
  }
  EXPECT_GT(detected, 50u);
}

TEST(VinsBinary, WriterRefusesDescriptorsOtherThan256Bits) {
  TempDir dir;
  for (const std::size_t code_size : {8u, 64u}) {
    try {
      save_vocabulary(random_vocabulary(4, 2, code_size, 2), dir.file("v.vins.bin"));
      ADD_FAILURE() << code_size << "-byte descriptors were written";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("256-bit descriptors only"), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(dir.file("v.vins.bin")), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("v.vins.bin")));
  }
  EXPECT_THROW(detail::format_vins_binary(random_vocabulary(4, 2, 64, 2).to_tree()),
               InvalidArgument);
}

TEST(VinsBinary, DamagedFilesAreRejectedNamingTheFile) {
  TempDir dir;
  const std::vector<std::uint8_t> valid = vins_file(3, 2, small_nodes(), small_words());
  write_file(dir.file("valid.data"), valid);
  ASSERT_EQ(load_vocabulary(dir.file("valid.data")).word_count(), 4u);

  EXPECT_FALSE(rejection(dir, "empty", {}).empty());
  EXPECT_REJECTED("header", std::vector<std::uint8_t>(valid.begin(), valid.begin() + 20),
                  "truncated");
  std::vector<std::uint8_t> cut(valid.begin(), valid.end() - 3);
  EXPECT_REJECTED("cut", cut, "(truncated)");
  std::vector<std::uint8_t> longer = valid;
  longer.push_back(7);
  EXPECT_REJECTED("longer", longer, "but the file has 297 bytes");

  auto with = [&](std::size_t offset, auto value) {
    std::vector<std::uint8_t> bytes = valid;
    detail::store_le(bytes.data() + offset, value);
    return bytes;
  };
  // Counts from a hostile header are checked against the size first.
  EXPECT_REJECTED("huge-nodes", with(16, std::int32_t{0x7fffffff}), "2147483647 nodes");
  EXPECT_REJECTED("huge-words", with(20, std::int32_t{0x7fffffff}), "(truncated)");
  EXPECT_REJECTED("negative-nodes", with(16, std::int32_t{-5}), "-5 nodes");
  EXPECT_REJECTED("no-words", with(20, std::int32_t{0}), "0 words");
  EXPECT_REJECTED("k", with(0, std::int32_t{0}), "branching factor k = 0");
  EXPECT_REJECTED("L", with(4, std::int32_t{99}), "depth L = 99");
  EXPECT_REJECTED("scoring", with(8, std::int32_t{6}), "scoring type 6");
  EXPECT_REJECTED("weighting", with(12, std::int32_t{-1}), "weighting type -1");
  // Too deep or too wide for the header's k and L.
  EXPECT_REJECTED("deep", with(4, std::int32_t{1}), "deeper than");
  EXPECT_REJECTED("wide", with(0, std::int32_t{1}), "more than the branching factor");

  const auto node_at = [](std::size_t record) { return 24 + 48 * record; };
  EXPECT_REJECTED("id-zero", with(node_at(2), std::int32_t{0}), "node id is outside 1..5");
  EXPECT_REJECTED("id-high", with(node_at(2), std::int32_t{6}), "node id is outside 1..5");
  EXPECT_REJECTED("id-twice", with(node_at(2), std::int32_t{2}), "appears twice");
  EXPECT_REJECTED("parent-high", with(node_at(3) + 4, std::int32_t{9}), "parent id 9");
  EXPECT_REJECTED("parent-negative", with(node_at(3) + 4, std::int32_t{-1}), "parent id -1");
  EXPECT_REJECTED("parent-self", with(node_at(3) + 4, std::int32_t{4}), "parent id 4");
  EXPECT_REJECTED("nan", with(node_at(1) + 8, std::numeric_limits<double>::quiet_NaN()),
                  "weight is not a finite float");
  EXPECT_REJECTED("too-big", with(node_at(1) + 8, 1e300), "weight is not a finite float");

  // Node 1 under node 3 and node 3 under node 1: a cycle apart from the root.
  std::vector<VinsNode> cycle = small_nodes();
  cycle[0].parent = 3;
  cycle[2].parent = 1;
  EXPECT_REJECTED("cycle", vins_file(3, 2, cycle, {{2, 0}, {4, 1}, {5, 2}}), "not reachable");
  // Siblings listed out of id order would be compared in another order by VINS.
  std::vector<VinsNode> swapped = small_nodes();
  std::swap(swapped[3], swapped[4]);
  EXPECT_REJECTED("siblings", vins_file(3, 2, swapped, small_words()), "sibling 5");

  const auto word_at = [](std::size_t record) { return 24 + 48 * 5 + 8 * record; };
  EXPECT_REJECTED("word-node-inner", with(word_at(1), std::int32_t{1}), "not a distinct leaf");
  EXPECT_REJECTED("word-node-twice", with(word_at(1), std::int32_t{2}), "not a distinct leaf");
  EXPECT_REJECTED("word-node-outside", with(word_at(1), std::int32_t{6}), "outside the tree");
  EXPECT_REJECTED("word-id-twice", with(word_at(1) + 4, std::int32_t{0}), "word id 0 is repeated");
  EXPECT_REJECTED("word-id-high", with(word_at(1) + 4, std::int32_t{4}), "outside 0..3");
  EXPECT_REJECTED("word-id-negative", with(word_at(1) + 4, std::int32_t{-2}), "outside the tree");
  std::vector<VinsWord> missing = small_words();
  missing.pop_back();
  EXPECT_REJECTED("missing-word", vins_file(3, 2, small_nodes(), missing),
                  "the word list has 3 entries but the tree has 4 leaves");
}

TEST(VinsBinary, WordIdsInAnotherOrderAreReadAndReported) {
  TempDir dir;
  write_file(dir.file("v.data"), vins_file(3, 2, small_nodes(), {{2, 3}, {3, 2}, {4, 1}, {5, 0}}));
  const detail::LoadedVocabulary loaded =
      detail::load_vocabulary_with_details(dir.file("v.data"), VocabularyFormat::kAuto);
  EXPECT_FALSE(loaded.word_ids_match);
  EXPECT_EQ(loaded.vocabulary.word_count(), 4u);
}

TEST(VinsBinary, ParserSurvivesEveryPrefixAndFlippedByte) {
  const std::vector<std::uint8_t> valid = vins_file(3, 2, small_nodes(), small_words());
  for (std::size_t cut = 0; cut < valid.size(); ++cut)
    EXPECT_THROW(detail::parse_vins_binary(valid.data(), cut, "prefix"), FileError) << cut;
  EXPECT_NO_THROW(detail::vocabulary_from_parsed(
      detail::parse_vins_binary(valid.data(), valid.size(), "whole"), "whole"));
  std::size_t accepted = 0;
  for (std::size_t at = 0; at < valid.size(); ++at) {
    for (const std::uint8_t mask : {0x01, 0x80, 0xFF}) {
      std::vector<std::uint8_t> bytes = valid;
      bytes[at] ^= mask;
      try {
        const Vocabulary v = detail::vocabulary_from_parsed(
            detail::parse_vins_binary(bytes.data(), bytes.size(), "flipped"), "flipped");
        const std::uint8_t probe[32] = {0xA5};
        EXPECT_LT(v.quantize(probe), v.word_count());
        ++accepted;
      } catch (const FileError&) {
      }
    }
  }
  EXPECT_GT(accepted, 0u);  // descriptor and weight bytes may change freely
}

}  // namespace
}  // namespace binbow
