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

#include "binbow/error.h"
#include "binbow/loop/corroboration.h"
#include "binbow/loop/run_record.h"
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

// The smallest run record detect-loops could have written: three frames.
nlohmann::json small_record() {
  nlohmann::json frames = nlohmann::json::array();
  for (int i = 0; i < 3; ++i)
    frames.push_back({{"file", std::to_string(i) + ".jpg"},
                      {"status", "no-database-results"},
                      {"match", -1},
                      {"score", 0},
                      {"normalised_score", 0},
                      {"inliers", 0}});
  return {{"format", "binbow-loop-run"},
          {"version", 1},
          {"inputs", {"frames"}},
          {"vocabulary", "v.bbw"},
          {"descriptor", "brief"},
          {"max_features", 0},
          {"params", nlohmann::json::object()},
          {"source", {{"stride", 1}, {"max_width", 0}, {"video_fps", 0}}},
          {"frames", frames},
          {"loops", nlohmann::json::array()},
          {"timing_ms", nlohmann::json::object()}};
}

// A sweep re-runs detection as the record says: values detect-loops never
// writes are refused, naming the record and the field.
TEST(RunRecord, ValuesDetectLoopsNeverWritesAreRefused) {
  test::TempDir dir;
  const std::string csv = dir.file("loops.csv");
  const std::string path = csv + ".run.json";
  write_text(csv, "query_index,match_index,query_file,match_file,score,inliers\n");
  write_text(dir.file("truth.txt"), "# 0-based\n2 0\n");
  write_text(path, small_record().dump());
  ASSERT_NO_THROW(loop::LoopRun::load(path));
  const std::vector<std::pair<std::string, nlohmann::json::json_pointer>> cases = {
      {"max_features", nlohmann::json::json_pointer("/max_features")},
      {"stride", nlohmann::json::json_pointer("/source/stride")},
      {"max_width", nlohmann::json::json_pointer("/source/max_width")},
      {"status", nlohmann::json::json_pointer("/frames/1/status")},
      {"accepted_by", nlohmann::json::json_pointer("/frames/1/accepted_by")},
      {"localised_from", nlohmann::json::json_pointer("/frames/1/localised_from")}};
  for (const auto& [field, pointer] : cases) {
    SCOPED_TRACE(field);
    nlohmann::json record = small_record();
    record[pointer] = field == "status" || field == "accepted_by" ? nlohmann::json("bogus")
                      : field == "stride"                         ? nlohmann::json(0)
                                                                  : nlohmann::json(-5);
    write_text(path, record.dump());
    try {
      loop::LoopRun::load(path);
      ADD_FAILURE() << "loaded";
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), path);
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
    std::string out;
    EXPECT_EQ(
        test::run_cli("evaluate --sweep --gt '" + dir.file("truth.txt") + "' '" + csv + "'", &out),
        1)
        << out;
    EXPECT_NE(out.find(path), std::string::npos) << out;
  }
}

// loops.csv and its record are renamed into place one after the other; a
// run killed between the two, or a loops.csv replaced or edited since, leaves
// a pair that disagrees: evaluate refuses it rather than report on the wrong
// run. Records from before the check are read with a warning.
TEST(RunRecord, EvaluateRefusesALoopsFileThatIsNotTheRecords) {
  const std::string samples = test::shared_data("rtabmap-samples/samples");
  const std::string truth = test::shared_data("rtabmap-samples/samples_GT.bmp");
  test::TempDir dir;
  const std::string csv = dir.file("loops.csv");
  const std::string record = csv + ".run.json";
  std::string out;
  ASSERT_EQ(test::run_cli(detect_loops_arguments(csv, samples), &out), 0) << out;
  const std::string evaluate = "evaluate --gt '" + truth + "' '" + csv + "'";
  ASSERT_EQ(test::run_cli(evaluate, &out), 0) << out;
  EXPECT_EQ(out.find("warning"), std::string::npos) << out;
  const double recall = test::printed_number(out, "recall");
  ASSERT_GT(recall, 0.3) << out;

  // The loops of another run: one loop fewer.
  const std::string loops = read_text(csv);
  ASSERT_GT(std::count(loops.begin(), loops.end(), '\n'), 2);
  const std::string fewer = loops.substr(0, loops.rfind('\n', loops.size() - 2) + 1);
  write_text(csv, fewer);
  EXPECT_EQ(test::run_cli(evaluate, &out), 1) << out;
  EXPECT_NE(out.find("binbow: error: " + csv + ": not the loops file written with the run record " +
                     record),
            std::string::npos)
      << out;

  // A record written before records named their loops file.
  nlohmann::json old = nlohmann::json::parse(read_text(record));
  ASSERT_TRUE(old.contains("loops_csv"));
  old.erase("loops_csv");
  write_text(record, old.dump());
  EXPECT_EQ(test::run_cli(evaluate, &out), 0) << out;
  EXPECT_NE(out.find("warning: " + record), std::string::npos) << out;
}

// The record names what accepted every loop, and evaluate prints it for the
// loops a ground truth calls false; records written before the key existed
// leave the evidence unknown.
TEST(RunRecord, EvaluateNamesTheEvidenceOfEachFalseLoop) {
  const std::string samples = test::shared_data("rtabmap-samples/samples");
  test::TempDir dir;
  const std::string csv = dir.file("loops.csv");
  const std::string record = csv + ".run.json";
  std::string out;
  ASSERT_EQ(test::run_cli(detect_loops_arguments(csv, samples), &out), 0) << out;
  const loop::LoopRun run = loop::LoopRun::load(record);
  std::size_t loops = 0;
  for (const loop::FrameRecord& f : run.frames) {
    SCOPED_TRACE(f.file);
    loop::LoopEvidence evidence;
    if (f.status == "loop-detected") {
      ++loops;
      ASSERT_TRUE(loop::parse_loop_evidence(f.accepted_by, &evidence)) << f.accepted_by;
      EXPECT_NE(evidence, loop::LoopEvidence::kNone);
    } else {
      EXPECT_EQ(f.accepted_by, "");
      EXPECT_EQ(f.localised_from, -1);
    }
  }
  ASSERT_GT(loops, 10u);

  // A ground truth that holds none of the loops: every one is false.
  write_text(dir.file("none.txt"), "# 0-based\n1 0\n");
  ASSERT_EQ(test::run_cli("evaluate --gt '" + dir.file("none.txt") + "' '" + csv + "'", &out), 0)
      << out;
  EXPECT_EQ(test::printed_number(out, "false loops"), double(loops)) << out;
  const auto lines_with = [&](const std::string& text) {
    std::size_t n = 0;
    for (std::size_t at = out.find(text); at != std::string::npos; at = out.find(text, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(lines_with(" inliers, accepted by "), loops) << out;

  nlohmann::json old = nlohmann::json::parse(read_text(record));
  for (nlohmann::json& frame : old["frames"]) frame.erase("accepted_by");
  write_text(record, old.dump());
  ASSERT_EQ(test::run_cli("evaluate --gt '" + dir.file("none.txt") + "' '" + csv + "'", &out), 0)
      << out;
  EXPECT_EQ(lines_with(" inliers, evidence unknown"), loops) << out;
}

}  // namespace
}  // namespace binbow
