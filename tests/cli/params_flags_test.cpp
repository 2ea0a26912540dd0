// `binbow detect-loops`: one flag per loop detector parameter, overriding
// --params, and --print-params writing a parameter file that --params reads
// back; commands take the extractor the vocabulary records.
#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "binbow/formats.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::run_cli;
using test::samples_folder;
using test::TempDir;

std::string flag_of(std::string key) {
  for (char& c : key)
    if (c == '_') c = '-';
  return "--" + key;
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// The JSON --print-params prints with `arguments`; a test failure if it fails.
nlohmann::ordered_json printed_params(const std::string& arguments) {
  std::string output;
  EXPECT_EQ(run_cli("detect-loops --print-params " + arguments, &output), 0) << output;
  return nlohmann::ordered_json::parse(output, nullptr, false);
}

TEST(CliParamFlags, EveryParameterKeyIsAFlag) {
  std::string help;
  ASSERT_EQ(run_cli("detect-loops --help", &help), 0) << help;
  const auto keys = nlohmann::ordered_json::parse(loop::LoopDetectorParams{}.to_json());
  ASSERT_GE(keys.size(), 20u);
  for (const auto& [key, value] : keys.items())
    EXPECT_NE(help.find(flag_of(key) + " "), std::string::npos) << key << " has no flag";
}

TEST(CliParamFlags, PrintParamsPrintsTheDefaults) {
  const auto printed = printed_params("");
  EXPECT_EQ(printed, nlohmann::ordered_json::parse(loop::LoopDetectorParams{}.to_json()));
}

TEST(CliParamFlags, FlagsOverrideTheParamsFileAndPrintedParamsReadBackIdentically) {
  TempDir dir;
  write_text(dir.file("base.json"), R"({"min_inliers": 15, "alpha": 0.2, "k": 1})");
  const auto printed =
      printed_params("--params '" + dir.file("base.json") +
                     "' --min-inliers 30 --geometric-check exhaustive --mutual-matching false "
                     "--max-neighbor-ratio 0.75");
  ASSERT_TRUE(printed.is_object());
  EXPECT_EQ(printed["min_inliers"], 30);  // the flag wins over the file
  EXPECT_EQ(printed["alpha"], 0.2);       // the file's key stays
  EXPECT_EQ(printed["k"], 1);
  EXPECT_EQ(printed["geometric_check"], "exhaustive");
  EXPECT_EQ(printed["mutual_matching"], false);
  EXPECT_EQ(printed["max_neighbor_ratio"], 0.75);

  write_text(dir.file("printed.json"), printed.dump(2));
  EXPECT_EQ(printed_params("--params '" + dir.file("printed.json") + "'"), printed);
  const loop::LoopDetectorParams loaded = loop::LoopDetectorParams::load(dir.file("printed.json"));
  EXPECT_EQ(nlohmann::ordered_json::parse(loaded.to_json()), printed);
}

TEST(CliParamFlags, BadValuesAreUsageErrors) {
  std::string output;
  EXPECT_EQ(run_cli("detect-loops --print-params --min-inliers many", &output), 1);
  EXPECT_NE(output.find("'many' is not a number"), std::string::npos) << output;
  EXPECT_EQ(run_cli("detect-loops --print-params --min-inliers 3", &output), 1);
  EXPECT_NE(output.find("min_inliers must be in [8"), std::string::npos) << output;
  EXPECT_EQ(run_cli("detect-loops --print-params --mutual-matching yes", &output), 1);
  EXPECT_EQ(run_cli("detect-loops --print-params --geometric-check ransac", &output), 1);
  EXPECT_NE(output.find("unknown geometric check"), std::string::npos) << output;
  EXPECT_EQ(run_cli("detect-loops --min-inliers 20 --resume-state x.bbld -o l.csv img", &output),
            1);
  EXPECT_NE(output.find("excludes"), std::string::npos) << output;
  EXPECT_EQ(run_cli("detect-loops " + samples_folder(), &output), 1);
  EXPECT_NE(output.find("--output is required"), std::string::npos) << output;
}

TEST(CliParamFlags, FlagsReachTheDetector) {
  TempDir dir;
  std::string output;
  ASSERT_EQ(run_cli("detect-loops --dislocal 7 --min-inliers 25 --stride 20 -o '" +
                        dir.file("loops.csv") + "' '" + samples_folder() + "'",
                    &output),
            0)
      << output;
  std::ifstream in(dir.file("loops.csv") + ".run.json");
  const auto record = nlohmann::json::parse(in);
  EXPECT_EQ(record["params"]["dislocal"], 7);
  EXPECT_EQ(record["params"]["min_inliers"], 25);
}

// Commands take the extractor from the vocabulary; --descriptor only overrides.
TEST(CliVocabularyDescriptor, CommandsUseTheExtractorTheVocabularyRecords) {
  TempDir dir;
  const std::string brief = test::source_path("data/vocab/brief_default.bbw");
  ASSERT_EQ(load_vocabulary(brief).descriptor(), "brief");
  std::string output;
  ASSERT_EQ(run_cli("detect-loops --vocab '" + brief + "' --stride 20 -o '" +
                        dir.file("loops.csv") + "' '" + samples_folder() + "'",
                    &output),
            0)
      << output;
  std::ifstream in(dir.file("loops.csv") + ".run.json");
  EXPECT_EQ(nlohmann::json::parse(in)["descriptor"], "brief");

  const std::string image = samples_folder() + "/1.jpg";
  ASSERT_EQ(
      run_cli("db build --vocab '" + brief + "' -o '" + dir.file("d.bbdb") + "' '" + image + "'",
              &output),
      0)
      << output;
  ASSERT_EQ(run_cli("db query '" + dir.file("d.bbdb") + "' '" + image + "'", &output), 0) << output;
  EXPECT_NE(output.find("1\t0\t"), std::string::npos) << output;  // finds itself first

  // An override that contradicts the vocabulary is an error.
  EXPECT_EQ(run_cli("db build --descriptor orb --vocab '" + brief + "' -o '" + dir.file("e.bbdb") +
                        "' '" + image + "'",
                    &output),
            1);
  EXPECT_NE(output.find("trained on brief descriptors, not orb"), std::string::npos) << output;
}

TEST(CliVocabularyDescriptor, OrbSlamFilesAreOrbVocabularies) {
  TempDir dir;
  VocabularyTree tree;
  tree.code_size = 32;
  tree.branching = 2;
  tree.levels = 1;
  tree.parent = {0, 0, 0};
  std::mt19937_64 rng(7);
  tree.descriptors.resize(tree.parent.size() * 32);
  for (std::uint8_t& byte : tree.descriptors) byte = static_cast<std::uint8_t>(rng());
  tree.weights = {0, 1.0f, 2.0f};
  save_vocabulary(Vocabulary::from_tree(tree), dir.file("voc.txt"));
  std::string output;
  ASSERT_EQ(run_cli("convert '" + dir.file("voc.txt") + "' '" + dir.file("voc.bbw") + "'", &output),
            0)
      << output;
  EXPECT_EQ(Vocabulary::load(dir.file("voc.bbw")).descriptor(), "orb");
  EXPECT_EQ(load_vocabulary(dir.file("voc.txt")).descriptor(), "orb");
}

}  // namespace
}  // namespace binbow
