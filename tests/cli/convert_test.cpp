// `binbow convert` and `binbow info` on every format, and their failures:
// exit status 1 and "binbow: error: <file>: <problem>" on stderr.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::cli_path;
using test::read_file;
using test::run_command;
using test::TempDir;
using test::write_file;

int binbow_cli(const std::string& arguments, std::string* output) {
  return run_command("'" + cli_path() + "' " + arguments, output);
}

Vocabulary small_vocabulary() {
  // A hand-made two-level tree: no dependence on the builder.
  VocabularyTree tree;
  tree.code_size = 32;
  tree.branching = 3;
  tree.levels = 2;
  tree.parent = {0, 0, 0, 0, 1, 1, 1, 2, 2};
  std::mt19937_64 rng(4);
  tree.descriptors.resize(tree.parent.size() * 32);
  for (std::uint8_t& byte : tree.descriptors) byte = static_cast<std::uint8_t>(rng());
  tree.weights = {0, 0, 0, 0.75f, 1.5f, 2.25f, 3.0f, 0.1f, 0.2f};
  return Vocabulary::from_tree(tree);
}

TEST(CliConvert, ConvertsBetweenEveryFormatAndBack) {
  TempDir dir;
  const Vocabulary vocabulary = small_vocabulary();
  vocabulary.save(dir.file("v.bbw"));
  std::string output;
  for (const char* name :
       {"v.txt", "v.bin", "v.yml", "v.yml.gz", "v.voc.gz", "v.dbow3", "v.fbow"}) {
    SCOPED_TRACE(name);
    ASSERT_EQ(binbow_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file(name) + "'", &output),
              0)
        << output;
    EXPECT_NE(output.find("wrote " + dir.file(name)), std::string::npos) << output;
    ASSERT_EQ(binbow_cli("info '" + dir.file(name) + "'", &output), 0) << output;
    EXPECT_NE(output.find("words: 6"), std::string::npos) << output;
    ASSERT_EQ(
        binbow_cli("convert '" + dir.file(name) + "' '" + dir.file("back.bbw") + "'", &output), 0)
        << output;
    if (std::string(name) != "v.fbow") {  // fbow does not keep L and the types
      EXPECT_EQ(read_file(dir.file("back.bbw")), read_file(dir.file("v.bbw")));
    }
  }
}

TEST(CliConvert, FromAndToOverrideDetection) {
  TempDir dir;
  small_vocabulary().save(dir.file("v.bbw"));
  std::string output;
  ASSERT_EQ(binbow_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file("orbvoc.data") +
                           "' --to orbslam-text",
                       &output),
            0)
      << output;
  EXPECT_EQ(load_vocabulary(dir.file("orbvoc.data"), VocabularyFormat::kOrbSlamText).word_count(),
            6u);
  EXPECT_EQ(binbow_cli("convert '" + dir.file("orbvoc.data") + "' '" + dir.file("x.bbw") +
                           "' --from dbow3",
                       &output),
            1);
  EXPECT_NE(output.find("binbow: error: " + dir.file("orbvoc.data") + ": "), std::string::npos)
      << output;
  EXPECT_EQ(
      binbow_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file("x.unknown") + "'", &output),
      1);
  EXPECT_NE(output.find("cannot tell the vocabulary format"), std::string::npos) << output;
  EXPECT_EQ(binbow_cli("convert '" + dir.file("v.bbw") + "' '" + dir.file("x.txt") + "' --to morse",
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
      EXPECT_EQ(binbow_cli(command, &output), 1) << output;
      EXPECT_NE(output.find("binbow: error: " + dir.file(c.name) + ": "), std::string::npos)
          << output;
      EXPECT_NE(output.find(c.problem), std::string::npos) << output;
    }
  }
  EXPECT_TRUE(read_file(dir.file("o.bbw")).empty());  // nothing half-written
}

}  // namespace
}  // namespace binbow
