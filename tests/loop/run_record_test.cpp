// detect-loops' two outputs, loops.csv and its run record: they appear
// together or not at all, and the record stays small however many loops
// are found.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "support/test_support.h"

namespace binbow {
namespace {

namespace fs = std::filesystem;

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::vector<std::string> directory_names(const std::string& directory) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// BRIEF with the bundled vocabulary: the fastest way through real frames.
std::string detect_loops_arguments(const std::string& output, const std::string& input) {
  const std::string vocabulary = test::source_path("data/vocab/brief_default.bbw");
  EXPECT_TRUE(fs::exists(vocabulary)) << vocabulary << " is missing (bundled in data/vocab)";
  return "detect-loops --descriptor brief --vocab '" + vocabulary + "' -o '" + output + "' '" +
         input + "'";
}

TEST(RunRecord, OutputsKeepTheirOldContentWhenTheRecordCannotBeWritten) {
  const std::string samples = test::shared_data("rtabmap-samples/samples");
  test::TempDir dir;
  const std::string csv = dir.file("loops.csv");
  const std::string record = csv + ".run.json";
  write_text(csv, "old loops\n");
  write_text(record, "old record\n");

  // A full disk, as a file size limit (in blocks of 512 or 1024 bytes,
  // depending on the shell): loops.csv (4 KB) fits, the record (170 KB)
  // does not. SIGXFSZ is ignored so that the write fails instead.
  std::string out;
  const int status = test::run_command("trap '' XFSZ; ulimit -f 64; exec '" + test::cli_path() +
                                           "' " + detect_loops_arguments(csv, samples),
                                       &out);
  EXPECT_EQ(status, 1) << out;
  EXPECT_NE(out.find("binbow: error: "), std::string::npos) << out;
  EXPECT_EQ(read_text(csv), "old loops\n");
  EXPECT_EQ(read_text(record), "old record\n");
  EXPECT_EQ(directory_names(dir.path()),
            (std::vector<std::string>{"loops.csv", "loops.csv.run.json"}))
      << "temporary files left behind";
}

TEST(RunRecord, LoopsCsvIsPutBackWhenTheRecordCannotReplaceItsTarget) {
  const std::string samples = test::shared_data("rtabmap-samples/samples");
  test::TempDir dir;
  const std::string csv = dir.file("loops.csv");
  write_text(csv, "old loops\n");
  // Written in full, the record cannot be renamed over a directory: by then
  // loops.csv has been replaced, and must get its old content back.
  fs::create_directory(csv + ".run.json");

  std::string out;
  EXPECT_EQ(test::run_cli(detect_loops_arguments(csv, samples), &out), 1) << out;
  EXPECT_NE(out.find("loops.csv.run.json"), std::string::npos) << out;
  EXPECT_EQ(read_text(csv), "old loops\n");
  EXPECT_TRUE(fs::is_directory(csv + ".run.json"));
  EXPECT_EQ(directory_names(dir.path()),
            (std::vector<std::string>{"loops.csv", "loops.csv.run.json"}))
      << "temporary files left behind";

  fs::remove(csv);
  fs::remove(csv + ".run.json");
  ASSERT_EQ(test::run_cli(detect_loops_arguments(csv, samples), &out), 0) << out;
  EXPECT_TRUE(fs::is_regular_file(csv));
  EXPECT_TRUE(fs::is_regular_file(csv + ".run.json"));
}

// The corridor six times over: every frame after the first pass closes a
// loop with its earlier copies, with nearly all its features as inliers.
TEST(RunRecord, KeepsOnlyTheLoopsAndInliersTheReportDraws) {
  const std::string samples = test::shared_data("rtabmap-samples/samples");
  test::TempDir dir;
  constexpr std::size_t kFrames = 84, kPasses = 6;
  std::ostringstream list, pairs;
  for (std::size_t pass = 0; pass < kPasses; ++pass)
    for (std::size_t i = 1; i <= kFrames; ++i) list << samples << '/' << i << ".jpg\n";
  for (std::size_t q = kFrames; q < kFrames * kPasses; ++q)
    for (std::size_t m = q % kFrames; m < q; m += kFrames) pairs << q << ' ' << m << '\n';
  write_text(dir.file("frames.txt"), list.str());
  write_text(dir.file("truth.txt"), "# 0-based\n" + pairs.str());
  const std::string csv = dir.file("loops.csv");

  std::string out;
  ASSERT_EQ(test::run_cli(detect_loops_arguments(csv, dir.file("frames.txt")), &out), 0) << out;
  const nlohmann::json record = nlohmann::json::parse(read_text(csv + ".run.json"));
  EXPECT_EQ(record.at("frames").size(), kFrames * kPasses);
  for (const auto& [stage, values] : record.at("timing_ms").items())
    EXPECT_EQ(values.size(), kFrames * kPasses) << stage;
  std::size_t loops = 0, most_inliers = 0;
  for (const auto& frame : record.at("frames")) {
    if (frame.at("status") != "loop-detected") continue;
    ++loops;
    most_inliers = std::max(most_inliers, frame.at("inliers").get<std::size_t>());
  }
  ASSERT_GT(loops, 300u) << "the test needs more loops than the report draws";
  ASSERT_GT(most_inliers, 200u) << "the test needs loops with more inliers than the report draws";
  ASSERT_EQ(record.at("loops").size(), 300u);
  for (const auto& loop : record.at("loops")) EXPECT_LE(loop.at("inliers").size(), 200u);

  // evaluate reads the record back.
  ASSERT_EQ(test::run_cli("evaluate --gt '" + dir.file("truth.txt") + "' '" + csv + "'", &out), 0)
      << out;
  EXPECT_GT(test::printed_number(out, "precision"), 0.5) << out;
}

}  // namespace
}  // namespace binbow
