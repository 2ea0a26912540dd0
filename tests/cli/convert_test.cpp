// `binbow convert` and `binbow info` on every format, and their failures:
// exit status 1 and "binbow: error: <file>: <problem>" on stderr.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <random>
#include <sstream>
#include <string>

#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::read_file;
using test::run_cli;
using test::TempDir;
using test::write_file;

TEST(CliConvert, ConvertsBetweenEveryFormatAndBack) {
  TempDir dir;
  const Vocabulary vocabulary = test::hand_made_vocabulary("orb");
  vocabulary.save(dir.file("v.bbw"));
  std::string output;
  for (const char* name :
       {"v.txt", "v.bin", "v.yml", "v.yml.gz", "v.voc.gz", "v.dbow3", "v.fbow"}) {
    SCOPED_TRACE(name);
    ASSERT_EQ(run_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file(name) + "'", &output), 0)
        << output;
    EXPECT_NE(output.find("wrote " + dir.file(name)), std::string::npos) << output;
    ASSERT_EQ(run_cli("info '" + dir.file(name) + "'", &output), 0) << output;
    EXPECT_NE(output.find("words: 6"), std::string::npos) << output;
    ASSERT_EQ(run_cli("convert '" + dir.file(name) + "' '" + dir.file("back.bbw") + "'", &output),
              0)
        << output;
    // Read back as ORB's (with a warning): the same vocabulary.
    if (std::string(name) != "v.fbow") {  // fbow does not keep L and the types
      EXPECT_EQ(read_file(dir.file("back.bbw")), read_file(dir.file("v.bbw")));
    }
  }
}

TEST(CliConvert, FromAndToOverrideDetection) {
  TempDir dir;
  test::hand_made_vocabulary().save(dir.file("v.bbw"));
  std::string output;
  ASSERT_EQ(run_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file("orbvoc.data") +
                        "' --to orbslam-text",
                    &output),
            0)
      << output;
  EXPECT_EQ(load_vocabulary(dir.file("orbvoc.data"), VocabularyFormat::kOrbSlamText).word_count(),
            6u);
  EXPECT_EQ(
      run_cli("convert '" + dir.file("orbvoc.data") + "' '" + dir.file("x.bbw") + "' --from dbow3",
              &output),
      1);
  EXPECT_NE(output.find("binbow: error: " + dir.file("orbvoc.data") + ": "), std::string::npos)
      << output;
  EXPECT_EQ(run_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file("x.unknown") + "'", &output),
            1);
  EXPECT_NE(output.find("cannot tell the vocabulary format"), std::string::npos) << output;
  EXPECT_EQ(run_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file("x.txt") + "' --to morse",
                    &output),
            1);
}

TEST(CliConvert, DamagedInputsExitWithOneAndNameTheFile) {
  TempDir dir;
  const struct {
    const char* name;
    std::string content;
    const char* problem;
  } cases[] = {
      {"empty.txt", "", "empty"},
      {"absurd.txt", "4000000000 4000000000 0 0\n", "k = 4000000000"},
      {"parent.txt", "2 1 0 0\n9 1 1 2 0.5\n", "line 2: parent id 9"},
      {"short.yml", "%YAML:1.0\n---\nvocabulary:\n   k: 2\n", "no `L`"},
      {"garbage.dbow3", "not a vocabulary at all", "signature"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    write_file(dir.file(c.name), {c.content.begin(), c.content.end()});
    std::string output;
    for (const std::string& command :
         {"info '" + dir.file(c.name) + "'",
          "convert '" + dir.file(c.name) + "' '" + dir.file("o.bbw") + "'"}) {
      EXPECT_EQ(run_cli(command, &output), 1) << output;
      EXPECT_NE(output.find("binbow: error: " + dir.file(c.name) + ": "), std::string::npos)
          << output;
      EXPECT_NE(output.find(c.problem), std::string::npos) << output;
    }
  }
  EXPECT_TRUE(read_file(dir.file("o.bbw")).empty());  // nothing half-written
}

// Formats other than .bbw record no extractor: --descriptor names it (and
// `convert` records it in a .bbw); without it the file is taken for ORB's,
// with one warning naming the file, the assumption and the flag.
TEST(CliConvert, DescriptorNamesTheExtractorOfFilesThatDoNotRecordIt) {
  TempDir dir;
  save_vocabulary(test::hand_made_vocabulary(), dir.file("v.yml"));
  std::string output;
  ASSERT_EQ(run_cli("convert --descriptor brief '" + dir.file("v.yml") + "' '" +
                        dir.file("brief.bbw") + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("descriptor: brief (recorded)"), std::string::npos) << output;
  EXPECT_EQ(output.find("warning"), std::string::npos) << output;
  ASSERT_EQ(run_cli("info '" + dir.file("brief.bbw") + "'", &output), 0) << output;
  EXPECT_NE(output.find("descriptor: brief\n"), std::string::npos) << output;

  const struct {
    std::string arguments;
    const char* problem;
  } refused[] = {
      {"--descriptor sift", "unknown feature type 'sift'"},
      {"--descriptor akaze", "akaze gives 488-bit descriptors, the vocabulary has 256-bit ones"},
      {"--descriptor BRIEF", "unknown feature type 'BRIEF'"},
  };
  for (const auto& c : refused) {
    EXPECT_EQ(run_cli("convert " + c.arguments + " '" + dir.file("v.yml") + "' '" +
                          dir.file("refused.bbw") + "'",
                      &output),
              1)
        << output;
    EXPECT_NE(output.find(c.problem), std::string::npos) << output;
    EXPECT_EQ(run_cli("info " + c.arguments + " '" + dir.file("v.yml") + "'", &output), 1)
        << output;
    EXPECT_NE(output.find(c.problem), std::string::npos) << output;
  }
  EXPECT_TRUE(read_file(dir.file("refused.bbw")).empty());

  const std::string warning = "binbow: warning: " + dir.file("v.yml") +
                              ": dbow2 files do not store the descriptor kind; assuming orb "
                              "(give --descriptor brief, or descriptor=\"brief\" in Python, if "
                              "it is BRIEF)\n";
  const auto count = [](const std::string& text, const std::string& part) {
    std::size_t n = 0;
    for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1))
      ++n;
    return n;
  };
  ASSERT_EQ(run_cli("info '" + dir.file("v.yml") + "'", &output), 0) << output;
  EXPECT_EQ(count(output, warning), 1u) << output;
  EXPECT_NE(output.find("descriptor: orb\n"), std::string::npos) << output;
  ASSERT_EQ(run_cli("info --descriptor brief '" + dir.file("v.yml") + "'", &output), 0) << output;
  EXPECT_EQ(output.find("warning"), std::string::npos) << output;
  EXPECT_NE(output.find("descriptor: brief\n"), std::string::npos) << output;

  // The image commands take it with their extractor flag.
  const std::string image = test::source_path("data/samples/rtabmap/samples/1.jpg");
  ASSERT_EQ(run_cli("db build --descriptor brief --vocab '" + dir.file("v.yml") + "' -o '" +
                        dir.file("d.bbdb") + "' '" + image + "'",
                    &output),
            0)
      << output;
  EXPECT_EQ(output.find("warning"), std::string::npos) << output;
  ASSERT_EQ(run_cli("db build --vocab '" + dir.file("v.yml") + "' -o '" + dir.file("d.bbdb") +
                        "' '" + image + "'",
                    &output),
            0)
      << output;
  EXPECT_EQ(count(output, warning), 1u) << output;
  EXPECT_EQ(count(output, "warning"), 1u) << output;
}

// A BRIEF vocabulary through ORB-SLAM text and back: byte-identical when the
// last step is told it is BRIEF, taken for ORB with one warning when not.
TEST(CliConvert, BriefThroughTextAndBackIsByteIdenticalWithDescriptor) {
  TempDir dir;
  test::hand_made_vocabulary("brief").save(dir.file("brief.bbw"));
  std::string output;
  ASSERT_EQ(
      run_cli("convert '" + dir.file("brief.bbw") + "' '" + dir.file("brief.txt") + "'", &output),
      0)
      << output;
  EXPECT_NE(output.find("note: orbslam-text files do not record the extractor: reading " +
                        dir.file("brief.txt") + " back assumes orb; give --descriptor brief then"),
            std::string::npos)
      << output;
  ASSERT_EQ(run_cli("convert --descriptor brief '" + dir.file("brief.txt") + "' '" +
                        dir.file("back.bbw") + "'",
                    &output),
            0)
      << output;
  EXPECT_EQ(output.find("warning"), std::string::npos) << output;
  EXPECT_EQ(read_file(dir.file("back.bbw")), read_file(dir.file("brief.bbw")));

  ASSERT_EQ(
      run_cli("convert '" + dir.file("brief.txt") + "' '" + dir.file("orb.bbw") + "'", &output), 0)
      << output;
  const std::string warning = "binbow: warning: " + dir.file("brief.txt") +
                              ": orbslam-text files do not store the descriptor kind; assuming "
                              "orb (give --descriptor brief";
  const std::size_t first = output.find(warning);
  EXPECT_NE(first, std::string::npos) << output;
  EXPECT_EQ(output.find("warning", first + warning.size()), std::string::npos) << output;  // once
  ASSERT_EQ(run_cli("info '" + dir.file("orb.bbw") + "'", &output), 0) << output;
  EXPECT_NE(output.find("descriptor: orb\n"), std::string::npos) << output;
}

// VINS-Mono/VINS-Fusion's binary layout: asked for by `--to vins` or a
// .vins.bin name, recognised by content, and usable wherever a vocabulary is.
TEST(CliConvert, WritesAndReadsVinsBinary) {
  TempDir dir;
  test::hand_made_vocabulary("brief").save(dir.file("v.bbw"));
  std::string output;
  ASSERT_EQ(
      run_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file("brief_k10L6.bin") + "' --to vins",
              &output),
      0)
      << output;
  EXPECT_NE(output.find("wrote " + dir.file("brief_k10L6.bin") + ": vins, 456 bytes"),
            std::string::npos)
      << output;
  ASSERT_EQ(run_cli("info '" + dir.file("brief_k10L6.bin") + "'", &output), 0) << output;
  EXPECT_NE(output.find("format: vins\n"), std::string::npos) << output;
  EXPECT_NE(output.find("words: 6\n"), std::string::npos) << output;
  // VINS vocabularies are BRIEF's by definition: no assumption, no warning.
  EXPECT_NE(output.find("descriptor: brief\n"), std::string::npos) << output;
  EXPECT_EQ(output.find("warning"), std::string::npos) << output;
  ASSERT_EQ(run_cli("convert '" + dir.file("brief_k10L6.bin") + "' '" + dir.file("back.bbw") + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("read " + dir.file("brief_k10L6.bin") + ": vins,"), std::string::npos)
      << output;
  EXPECT_EQ(read_file(dir.file("back.bbw")), read_file(dir.file("v.bbw")));
  ASSERT_EQ(
      run_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file("v.vins.bin") + "'", &output), 0)
      << output;
  EXPECT_EQ(read_file(dir.file("v.vins.bin")), read_file(dir.file("brief_k10L6.bin")));

  // Gzipped under a .bin name, only the decompressed size tells it from ORB-SLAM binary.
  ASSERT_EQ(run_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file("v.bin.gz") + "' --to vins",
                    &output),
            0)
      << output;
  ASSERT_EQ(run_cli("info '" + dir.file("v.bin.gz") + "'", &output), 0) << output;
  EXPECT_NE(output.find("format: vins\n"), std::string::npos) << output;

  // --vocab takes it like any other format.
  const std::string image = test::source_path("data/samples/rtabmap/samples/1.jpg");
  ASSERT_EQ(run_cli("db build --descriptor brief --vocab '" + dir.file("brief_k10L6.bin") +
                        "' -o '" + dir.file("d.bbdb") + "' '" + image + "'",
                    &output),
            0)
      << output;

  // VINS computes BRIEF: an ORB vocabulary is written, with a note.
  test::hand_made_vocabulary().with_descriptor("orb").save(dir.file("orb.bbw"));
  ASSERT_EQ(
      run_cli("convert '" + dir.file("orb.bbw") + "' '" + dir.file("orb.vins.bin") + "'", &output),
      0)
      << output;
  EXPECT_NE(output.find("note: VINS files do not record the extractor"), std::string::npos)
      << output;

  // Only 256-bit descriptors fit.
  VocabularyTree wide = test::hand_made_vocabulary().to_tree();
  wide.code_size = 64;
  wide.descriptors.resize(wide.node_count() * 64, 1);
  Vocabulary::from_tree(wide).save(dir.file("wide.bbw"));
  EXPECT_EQ(run_cli("convert '" + dir.file("wide.bbw") + "' '" + dir.file("wide.vins.bin") + "'",
                    &output),
            1);
  EXPECT_NE(output.find("binbow: error: cannot write " + dir.file("wide.vins.bin") +
                        " as a VINS vocabulary: the format holds 256-bit descriptors only, this "
                        "vocabulary has 512-bit ones"),
            std::string::npos)
      << output;
  EXPECT_TRUE(read_file(dir.file("wide.vins.bin")).empty());
}

// DBoW2 users must be able to go back: read our DBoW2 YAML (plain, gzip,
// bytes and bits) through OpenCV's FileStorage exactly as DBoW2's
// TemplatedVocabulary::load does, and compare with the vocabulary.
TEST(CliConvert, Dbow2YamlOutputReadsBackThroughOpenCvFileStorage) {
  TempDir dir;
  const Vocabulary vocabulary = test::hand_made_vocabulary();
  vocabulary.save(dir.file("v.bbw"));
  const VocabularyTree tree = vocabulary.to_tree();
  std::string output;
  for (const char* name : {"orb.yml", "brief.voc.gz"}) {
    SCOPED_TRACE(name);
    const bool bits = std::string(name) == "brief.voc.gz";
    ASSERT_EQ(run_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file(name) +
                          "' --descriptors " + (bits ? "bits" : "bytes"),
                      &output),
              0)
        << output;
    cv::FileStorage fs(dir.file(name), cv::FileStorage::READ);
    ASSERT_TRUE(fs.isOpened());
    const cv::FileNode voc = fs["vocabulary"];
    EXPECT_EQ(static_cast<int>(voc["k"]), 3);
    EXPECT_EQ(static_cast<int>(voc["L"]), 2);
    EXPECT_EQ(static_cast<int>(voc["scoringType"]), 0);
    EXPECT_EQ(static_cast<int>(voc["weightingType"]), 0);
    const cv::FileNode nodes = voc["nodes"];
    ASSERT_EQ(nodes.size(), tree.node_count() - 1);
    for (auto it = nodes.begin(); it != nodes.end(); ++it) {
      const int id = static_cast<int>((*it)["nodeId"]);
      ASSERT_GT(id, 0);
      ASSERT_LT(static_cast<std::size_t>(id), tree.node_count());
      EXPECT_EQ(static_cast<int>((*it)["parentId"]), static_cast<int>(tree.parent[id]));
      EXPECT_EQ(static_cast<float>(static_cast<double>((*it)["weight"])), tree.weights[id]);
      const std::string text = static_cast<std::string>((*it)["descriptor"]);
      std::vector<std::uint8_t> bytes(32, 0);
      if (bits) {  // DBoW2 FBrief: boost::dynamic_bitset from the string, MSB first
        ASSERT_EQ(text.size(), 256u);
        for (std::size_t i = 0; i < 256; ++i)
          if (text[255 - i] == '1') bytes[i / 8] |= static_cast<std::uint8_t>(1u << (i % 8));
      } else {  // DBoW2 FORB: decimal bytes through a stringstream
        std::istringstream in(text);
        for (std::uint8_t& byte : bytes) {
          int value = -1;
          in >> value;
          byte = static_cast<std::uint8_t>(value);
        }
      }
      EXPECT_EQ(bytes, std::vector<std::uint8_t>(tree.descriptors.begin() + id * 32,
                                                 tree.descriptors.begin() + id * 32 + 32));
    }
    const cv::FileNode words = voc["words"];
    ASSERT_EQ(words.size(), vocabulary.word_count());
    const std::vector<NodeId> word_nodes = vocabulary.word_nodes();
    for (auto it = words.begin(); it != words.end(); ++it)
      EXPECT_EQ(static_cast<int>((*it)["nodeId"]),
                static_cast<int>(word_nodes[static_cast<int>((*it)["wordId"])]));
  }
}

}  // namespace
}  // namespace binbow
