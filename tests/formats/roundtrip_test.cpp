// Every writer's output reads back as the same tree; text round trips are
// byte-identical; formats are recognised by content.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "formats/codecs.h"
#include "formats/loader.h"
#include "support/random_tree.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::read_file;
using test::TempDir;
using test::write_file;

void expect_same_tree(const VocabularyTree& expected, const VocabularyTree& actual) {
  EXPECT_EQ(expected.code_size, actual.code_size);
  EXPECT_EQ(expected.branching, actual.branching);
  EXPECT_EQ(expected.levels, actual.levels);
  EXPECT_EQ(expected.weighting, actual.weighting);
  EXPECT_EQ(expected.scoring, actual.scoring);
  ASSERT_EQ(expected.node_count(), actual.node_count());
  EXPECT_EQ(expected.parent, actual.parent);
  EXPECT_EQ(expected.descriptors, actual.descriptors);
  EXPECT_EQ(expected.weights, actual.weights);  // bitwise: every format keeps float weights
}

std::uint32_t tree_depth(const VocabularyTree& tree) {
  std::vector<std::uint32_t> depth(tree.node_count(), 0);
  std::uint32_t deepest = 0;
  for (std::size_t i = 1; i < tree.node_count(); ++i) {
    depth[i] = depth[tree.parent[i]] + 1;  // parents precede children in DBoW2 order
    deepest = std::max(deepest, depth[i]);
  }
  return deepest;
}

Vocabulary random_vocabulary(std::uint32_t k, std::uint32_t levels, std::size_t code_size,
                             std::uint64_t seed, Weighting weighting = Weighting::kTfIdf,
                             Scoring scoring = Scoring::kL1) {
  std::mt19937_64 rng(seed);
  VocabularyTree tree = test::random_tree(k, levels, code_size, rng);
  tree.weighting = weighting;
  tree.scoring = scoring;
  return Vocabulary::from_tree(tree);
}

struct Case {
  const char* file;
  VocabularyFormat format;
  bool brief_bits;
};
const Case kCases[] = {
    {"v.bbw", VocabularyFormat::kBinbow, false},
    {"v.txt", VocabularyFormat::kOrbSlamText, false},
    {"v.bin", VocabularyFormat::kOrbSlamBinary, false},
    {"v.yml", VocabularyFormat::kDbow2Yaml, false},
    {"bits.yml", VocabularyFormat::kDbow2Yaml, true},
    {"v.yml.gz", VocabularyFormat::kDbow2Yaml, false},
    {"v.voc.gz", VocabularyFormat::kDbow2Yaml, true},
    {"v.dbow3", VocabularyFormat::kDbow3, false},
    {"v.fbow", VocabularyFormat::kFbow, false},
};

TEST(FormatsRoundTrip, EveryWriterReadsBackTheSameTree) {
  TempDir dir;
  for (const std::size_t code_size : {32u, 64u, 5u}) {
    const Vocabulary vocabulary = random_vocabulary(
        code_size == 5 ? 3 : 6, 4, code_size, 7 + code_size, Weighting::kIdf, Scoring::kChiSquare);
    VocabularyTree expected = vocabulary.to_tree();
    for (const Case& c : kCases) {
      SCOPED_TRACE(std::string(c.file) + " code size " + std::to_string(code_size));
      const std::string path = dir.file(c.file);
      save_vocabulary(vocabulary, path, VocabularyFormat::kAuto, c.brief_bits);
      EXPECT_EQ(detect_vocabulary_format(path), c.format);
      const detail::LoadedVocabulary loaded =
          detail::load_vocabulary_with_details(path, VocabularyFormat::kAuto);
      EXPECT_EQ(loaded.format, c.format);
      EXPECT_TRUE(loaded.word_ids_match);
      if (c.format == VocabularyFormat::kDbow2Yaml) {
        EXPECT_EQ(loaded.descriptor_text,
                  c.brief_bits ? detail::DescriptorText::kBits : detail::DescriptorText::kBytes);
      }
      VocabularyTree want = expected;
      if (c.format == VocabularyFormat::kFbow) {  // fbow keeps neither L nor the types
        want.levels = tree_depth(expected);
        want.weighting = Weighting::kTfIdf;
        want.scoring = Scoring::kL1;
      }
      expect_same_tree(want, loaded.vocabulary.to_tree());
      if (c.format != VocabularyFormat::kFbow) {
        EXPECT_EQ(loaded.vocabulary.checksum(), vocabulary.checksum());
      }
    }
  }
}

TEST(FormatsRoundTrip, BuiltVocabularyTransformsIdenticallyAfterEveryFormat) {
  std::mt19937_64 rng(21);
  std::vector<DescriptorMatrix> images;
  std::vector<DescriptorView> views;
  for (int i = 0; i < 12; ++i)
    images.push_back(test::clustered_descriptors(150, 32, 40, 0.05, rng));
  for (const DescriptorMatrix& image : images) views.push_back(image.view());
  BuildOptions options;
  options.branching = 6;
  options.levels = 3;
  options.threads = 1;
  const Vocabulary vocabulary = Vocabulary::build(views, options);
  const DescriptorMatrix queries = test::clustered_descriptors(300, 32, 40, 0.1, rng);
  BowVector expected;
  vocabulary.transform(queries, expected);
  TempDir dir;
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.file);
    save_vocabulary(vocabulary, dir.file(c.file), VocabularyFormat::kAuto, c.brief_bits);
    BowVector bow;
    load_vocabulary(dir.file(c.file)).transform(queries, bow);
    EXPECT_FALSE(bow.empty());
    EXPECT_EQ(bow.entries(), expected.entries());
  }
}

TEST(FormatsRoundTrip, BbwToTextToBbwIsByteIdentical) {
  TempDir dir;
  // Only .bbw records the extractor: told it when reading the others back, a
  // vocabulary goes round unchanged.
  const Vocabulary vocabulary = random_vocabulary(10, 4, 32, 11).with_descriptor("brief");
  vocabulary.save(dir.file("a.bbw"));
  save_vocabulary(load_vocabulary(dir.file("a.bbw")), dir.file("a.txt"));
  save_vocabulary(load_vocabulary(dir.file("a.txt"), VocabularyFormat::kAuto, "brief"),
                  dir.file("b.bbw"));
  save_vocabulary(load_vocabulary(dir.file("b.bbw")), dir.file("b.txt"));
  EXPECT_EQ(read_file(dir.file("a.bbw")), read_file(dir.file("b.bbw")));
  EXPECT_EQ(read_file(dir.file("a.txt")), read_file(dir.file("b.txt")));
  // Through every other writer as well.
  for (const char* name : {"c.yml", "c.yml.gz", "c.dbow3", "c.bin", "c.vins.bin"}) {
    SCOPED_TRACE(name);
    save_vocabulary(vocabulary, dir.file(name));
    save_vocabulary(load_vocabulary(dir.file(name), VocabularyFormat::kAuto, "brief"),
                    dir.file("c.bbw"));
    EXPECT_EQ(read_file(dir.file("a.bbw")), read_file(dir.file("c.bbw")));
  }
}

// A file that does not record the extractor is read as ORB's when its
// descriptors are 256-bit, with one warning naming the file, the assumption
// and how to say otherwise; told the extractor, it takes it without a word.
TEST(FormatsRoundTrip, AFileThatDoesNotRecordTheExtractorSaysWhatIsAssumed) {
  TempDir dir;
  const Vocabulary brief = random_vocabulary(6, 3, 32, 5).with_descriptor("brief");
  const Vocabulary wide = random_vocabulary(6, 3, 64, 5);
  brief.with_descriptor("").save(dir.file("unnamed.bbw"));
  std::vector<std::string> warnings;
  set_warning_handler([&](const std::string& message) { warnings.push_back(message); });
  struct Expected {
    const char* file;
    const char* says;
  };
  for (const Expected& e :
       {Expected{"v.txt", "orbslam-text files do"}, Expected{"v.bin", "orbslam-binary files do"},
        Expected{"v.yml.gz", "dbow2 files do"}, Expected{"v.dbow3", "dbow3 files do"},
        Expected{"v.fbow", "fbow files do"}, Expected{"unnamed.bbw", "the file does"}}) {
    SCOPED_TRACE(e.file);
    const std::string path = dir.file(e.file);
    if (std::string(e.file) != "unnamed.bbw") save_vocabulary(brief, path);
    warnings.clear();
    EXPECT_EQ(load_vocabulary(path).descriptor(), "orb");
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0], path + ": " + e.says +
                               " not store the descriptor kind; assuming orb (give --descriptor "
                               "brief, or descriptor=\"brief\" in Python, if it is BRIEF)");
    warnings.clear();
    EXPECT_EQ(load_vocabulary(path, VocabularyFormat::kAuto, "brief").descriptor(), "brief");
    EXPECT_TRUE(warnings.empty());
    // The DBoW2 API's loading names nothing and says nothing.
    EXPECT_EQ(detail::load_vocabulary_with_details(path, VocabularyFormat::kAuto, "",
                                                   detail::UnrecordedDescriptor::kLeaveBlank)
                  .vocabulary.descriptor(),
              "");
    EXPECT_TRUE(warnings.empty());
  }
  // Descriptors of another length are not ORB's: nothing is assumed.
  save_vocabulary(wide, dir.file("wide.yml"));
  warnings.clear();
  EXPECT_EQ(load_vocabulary(dir.file("wide.yml")).descriptor(), "");
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], dir.file("wide.yml") +
                             ": dbow2 files do not store the descriptor kind, and its 512-bit "
                             "descriptors are not orb's: give it with --descriptor NAME "
                             "(descriptor=\"NAME\" in Python)");
  // A .bbw that records its extractor keeps it, silently.
  brief.save(dir.file("named.bbw"));
  warnings.clear();
  EXPECT_EQ(load_vocabulary(dir.file("named.bbw"), VocabularyFormat::kAuto, "orb").descriptor(),
            "brief");
  EXPECT_TRUE(warnings.empty());
  set_warning_handler(nullptr);
  EXPECT_THROW(load_vocabulary(dir.file("v.txt"), VocabularyFormat::kAuto, "BRIEF"),
               InvalidArgument);
}

TEST(FormatsRoundTrip, TextMatchesOrbSlamLayoutWithShortestWeights) {
  VocabularyTree tree;
  tree.code_size = 2;
  tree.branching = 2;
  tree.levels = 2;
  tree.scoring = Scoring::kL2;
  tree.weighting = Weighting::kTf;
  tree.parent = {0, 0, 0, 1, 1};
  tree.descriptors = {0, 0, 1, 2, 255, 0, 7, 8, 9, 10};
  tree.weights = {0, 0, 0.1f, 2.5f, 1e-7f};
  const std::vector<std::uint8_t> text =
      detail::format_orbslam_text(Vocabulary::from_tree(tree).to_tree());
  EXPECT_EQ(std::string(text.begin(), text.end()),
            "2 2  1 1\n"
            "0 0 1 2  0\n"
            "0 1 255 0  0.1\n"
            "1 1 7 8  2.5\n"
            "1 1 9 10  1e-07\n");
}

TEST(FormatsRoundTrip, TextParserToleratesCrLfTabsAndTrailingBlankLines) {
  const std::string text =
      "2 2 0 0\r\n0 0 1 2 0\r\n0 1 3\t4 0.5\r\n1 1 5 6   1.25\r\n1 1 7 8 2\r\n\r\n\n";
  const detail::ParsedVocabulary parsed = detail::parse_orbslam_text(
      reinterpret_cast<const std::uint8_t*>(text.data()), text.size(), "crlf.txt");
  EXPECT_EQ(parsed.tree.node_count(), 5u);
  EXPECT_EQ(parsed.tree.weights[3], 1.25f);
  EXPECT_EQ(parsed.tree.descriptors[2 * 2 + 1], 4);
}

TEST(FormatsRoundTrip, ParallelTextParseEqualsSequential) {
  std::mt19937_64 rng(5);
  const Vocabulary vocabulary = Vocabulary::from_tree(test::random_tree(8, 5, 32, rng, 0.0));
  const std::vector<std::uint8_t> text = detail::format_orbslam_text(vocabulary.to_tree());
  ASSERT_GT(text.size(), 1u << 20);  // above the threshold where threads are used
  const auto one = detail::parse_orbslam_text(text.data(), text.size(), "t", 1);
  for (const unsigned threads : {2u, 3u, 7u}) {
    const auto many = detail::parse_orbslam_text(text.data(), text.size(), "t", threads);
    expect_same_tree(one.tree, many.tree);
  }
  expect_same_tree(vocabulary.to_tree(), Vocabulary::from_tree(one.tree).to_tree());
}

TEST(FormatsRoundTrip, WordListInAnotherOrderIsAcceptedAndReported) {
  const std::string yaml =
      "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 1\n   scoringType: 0\n   weightingType: 0\n"
      "   nodes:\n      - { nodeId:1, parentId:0, weight:1.5, descriptor:\"1 2 \" }\n"
      "      - { descriptor:\"3 4 \", weight:2., parentId:0, nodeId:2 }\n"
      "   words:\n      - { wordId:1, nodeId:1 }\n      - { wordId:0, nodeId:2 }\n";
  const auto parsed = detail::parse_dbow2_yaml(reinterpret_cast<const std::uint8_t*>(yaml.data()),
                                               yaml.size(), "w.yml");
  EXPECT_FALSE(parsed.word_ids_match);
  EXPECT_EQ(parsed.tree.weights[2], 2.0f);
  EXPECT_EQ(parsed.tree.descriptors[2 * 2], 3);
}

TEST(FormatsRoundTrip, Dbow3YamlDescriptorsAreRead) {
  const std::string yaml =
      "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 1\n   scoringType: 1\n   weightingType: 2\n"
      "   nodes:\n      - { nodeId:1, parentId:0, weight:1.5, descriptor:\"dbw3 0 3 1 2 3 \" }\n"
      "      - { nodeId:2, parentId:0, weight:2.5, descriptor:\"dbw3 0 3 4 5 6 \" }\n"
      "   words:\n      - { wordId:0, nodeId:1 }\n      - { wordId:1, nodeId:2 }\n";
  const auto parsed = detail::parse_dbow2_yaml(reinterpret_cast<const std::uint8_t*>(yaml.data()),
                                               yaml.size(), "d3.yml");
  EXPECT_EQ(parsed.tree.code_size, 3u);
  EXPECT_EQ(parsed.tree.scoring, Scoring::kL2);
  EXPECT_EQ(parsed.tree.weighting, Weighting::kIdf);
  EXPECT_EQ(parsed.tree.descriptors[2 * 3 + 2], 6);
}

// Early DBoW3 versions wrote "<OpenCV type> <cols> v0 ..." without "dbw3".
std::string early_dbow3_yaml(const std::string& first, const std::string& second) {
  return "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 1\n   scoringType: 0\n   weightingType: 0\n"
         "   nodes:\n      - { nodeId:1, parentId:0, weight:1.5, descriptor:\"" +
         first + "\" }\n      - { nodeId:2, parentId:0, weight:2.5, descriptor:\"" + second +
         "\" }\n   words:\n      - { wordId:0, nodeId:1 }\n      - { wordId:1, nodeId:2 }\n";
}

detail::ParsedVocabulary parse_yaml(const std::string& yaml) {
  return detail::parse_dbow2_yaml(reinterpret_cast<const std::uint8_t*>(yaml.data()), yaml.size(),
                                  "early.yml");
}

TEST(FormatsRoundTrip, EarlyDbow3YamlDescriptorsWithoutMagicAreRead) {
  // ORB: 32 bytes, "0 32" in front of each.
  std::string first = "0 32 ", second = "0 32 ";
  for (int i = 0; i < 32; ++i) {
    first += std::to_string(i * 7) + " ";
    second += std::to_string(255 - i) + " ";
  }
  TempDir dir;
  write_file(dir.file("early.yml"), [&] {
    const std::string yaml = early_dbow3_yaml(first, second);
    return std::vector<std::uint8_t>(yaml.begin(), yaml.end());
  }());
  const Vocabulary vocabulary = load_vocabulary(dir.file("early.yml"));
  EXPECT_EQ(vocabulary.code_size(), 32u);
  EXPECT_EQ(vocabulary.node_descriptor(1)[0], 0);
  EXPECT_EQ(vocabulary.node_descriptor(1)[31], 31 * 7);
  EXPECT_EQ(vocabulary.node_descriptor(2)[0], 255);

  // Only when every node has the layout: otherwise the values are DBoW2 bytes.
  const auto mixed = parse_yaml(early_dbow3_yaml("0 3 1 2 3 ", "7 3 4 5 6 "));
  EXPECT_EQ(mixed.tree.code_size, 5u);
  EXPECT_EQ(mixed.tree.descriptors[1 * 5 + 1], 3);
  const auto counted = parse_yaml(early_dbow3_yaml("0 3 1 2 3 ", "0 3 4 5 6 "));
  EXPECT_EQ(counted.tree.code_size, 3u);
  EXPECT_EQ(counted.tree.descriptors[2 * 3 + 2], 6);

  // Float descriptors of that layout are named as such.
  try {
    parse_yaml(early_dbow3_yaml("5 3 0.5 0.25 1 ", "5 3 0.125 2 3 "));
    ADD_FAILURE() << "float descriptors accepted";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("float descriptors (OpenCV type 5) are not supported"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(parse_yaml(early_dbow3_yaml("dbw3 5 2 0.5 0.25 ", "dbw3 5 2 1.5 2 ")), FileError);
}

TEST(Formats, NamesExtensionsAndDetection) {
  for (const VocabularyFormat format :
       {VocabularyFormat::kAuto, VocabularyFormat::kBinbow, VocabularyFormat::kDbow2Yaml,
        VocabularyFormat::kOrbSlamText, VocabularyFormat::kOrbSlamBinary, VocabularyFormat::kDbow3,
        VocabularyFormat::kFbow})
    EXPECT_EQ(parse_vocabulary_format(to_string(format)), format);
  EXPECT_EQ(parse_vocabulary_format("ORBSLAM_TEXT"), VocabularyFormat::kOrbSlamText);
  EXPECT_THROW(parse_vocabulary_format("xml"), InvalidArgument);
  EXPECT_EQ(format_for_output("a/ORBvoc.txt"), VocabularyFormat::kOrbSlamText);
  EXPECT_EQ(format_for_output("x.BBW"), VocabularyFormat::kBinbow);
  EXPECT_EQ(format_for_output("x.voc.gz"), VocabularyFormat::kDbow2Yaml);
  EXPECT_EQ(format_for_output("x.yml.gz"), VocabularyFormat::kDbow2Yaml);
  EXPECT_EQ(format_for_output("x.dbow3"), VocabularyFormat::kDbow3);
  EXPECT_EQ(format_for_output("x.fbow"), VocabularyFormat::kFbow);
  EXPECT_THROW(format_for_output("x.gz"), InvalidArgument);
  EXPECT_THROW(format_for_output("ORBvoc.txt.tar.gz"), InvalidArgument);
  EXPECT_EQ(format_for_output("ORBvoc.txt.gz"), VocabularyFormat::kOrbSlamText);
  EXPECT_THROW(format_for_output("x"), InvalidArgument);

  // Content wins over a misleading extension.
  TempDir dir;
  const Vocabulary vocabulary = random_vocabulary(4, 3, 32, 3);
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.file);
    save_vocabulary(vocabulary, dir.file(c.file));
    write_file(dir.file("renamed.fbow"), read_file(dir.file(c.file)));
    EXPECT_EQ(detect_vocabulary_format(dir.file("renamed.fbow")), c.format);
    EXPECT_EQ(load_vocabulary(dir.file("renamed.fbow")).word_count(), vocabulary.word_count());
  }
  // --from forces a parser.
  save_vocabulary(vocabulary, dir.file("v.txt"));
  EXPECT_THROW(load_vocabulary(dir.file("v.txt"), VocabularyFormat::kDbow3), FileError);
  EXPECT_EQ(load_vocabulary(dir.file("v.txt"), VocabularyFormat::kOrbSlamText).checksum(),
            vocabulary.checksum());
}

TEST(Formats, EveryFormatMayBeGzippedOrInATarGz) {
  TempDir dir;
  const Vocabulary vocabulary = random_vocabulary(4, 3, 32, 8);
  for (const Case& c : kCases) {
    SCOPED_TRACE(c.file);
    const std::string name = c.file;
    const bool already_gzip = name.size() > 3 && name.compare(name.size() - 3, 3, ".gz") == 0;
    const std::string gz = dir.file(already_gzip ? name : name + ".gz");
    save_vocabulary(vocabulary, gz);
    EXPECT_EQ(detect_vocabulary_format(gz), c.format);
    const detail::LoadedVocabulary loaded =
        detail::load_vocabulary_with_details(gz, VocabularyFormat::kAuto);
    EXPECT_TRUE(loaded.compressed);
    EXPECT_EQ(loaded.format, c.format);
    if (c.format != VocabularyFormat::kFbow) {
      EXPECT_EQ(loaded.vocabulary.checksum(), vocabulary.checksum());
    }
  }
  // ORB-SLAM ships Vocabulary/ORBvoc.txt.tar.gz: a directory entry, then the file.
  std::filesystem::create_directory(dir.file("Vocabulary"));
  save_vocabulary(vocabulary, dir.file("Vocabulary/ORBvoc.txt"));
  std::string output;
  ASSERT_EQ(test::run_command("tar czf '" + dir.file("ORBvoc.txt.tar.gz") + "' -C '" + dir.path() +
                                  "' Vocabulary",
                              &output),
            0)
      << output;
  EXPECT_EQ(detect_vocabulary_format(dir.file("ORBvoc.txt.tar.gz")),
            VocabularyFormat::kOrbSlamText);
  EXPECT_EQ(load_vocabulary(dir.file("ORBvoc.txt.tar.gz")).checksum(), vocabulary.checksum());
  // A tar.gz of an ORB-SLAM binary file: recognised by its size in the tar header.
  save_vocabulary(vocabulary, dir.file("Vocabulary/ORBvoc.bin"));
  std::filesystem::remove(dir.file("Vocabulary/ORBvoc.txt"));
  ASSERT_EQ(
      test::run_command("tar czf '" + dir.file("voc.data") + "' -C '" + dir.path() + "' Vocabulary",
                        &output),
      0);
  EXPECT_EQ(detect_vocabulary_format(dir.file("voc.data")), VocabularyFormat::kOrbSlamBinary);
  EXPECT_EQ(load_vocabulary(dir.file("voc.data")).checksum(), vocabulary.checksum());
}

TEST(Formats, SavingIsAtomicAndRejectsEmptyVocabularies) {
  TempDir dir;
  EXPECT_THROW(save_vocabulary(Vocabulary(), dir.file("e.txt")), InvalidArgument);
  EXPECT_TRUE(read_file(dir.file("e.txt")).empty());
  save_vocabulary(random_vocabulary(3, 2, 32, 1), dir.file("no/such/dir/v.txt"));  // folders made
  EXPECT_THROW(save_vocabulary(random_vocabulary(3, 2, 32, 1), dir.file("no/such/dir/v.txt/w.txt")),
               FileError);
}

}  // namespace
}  // namespace binbow
