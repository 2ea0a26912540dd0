// --threads: detect-loops, db build/add/query and bench read and describe
// frames on several threads, and print, write and fail exactly as with one.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "support/test_support.h"

namespace binbow {
namespace {

using test::run_cli;
using test::samples_folder;
using test::shared_data;
using test::TempDir;

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << "cannot read " << path;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// `text` with every occurrence of `from` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos;
       at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

// What a run with `threads` threads printed and wrote into its own directory
// (named after the thread count, so that the runs' paths differ only there).
struct CliRun {
  int status = 0;
  std::string output;  // stdout and stderr, the run's directory as "RUN", durations as "T"
  std::string directory;
};

CliRun run_in(const TempDir& dir, unsigned threads, const std::string& arguments) {
  CliRun run;
  run.directory = dir.file("threads" + std::to_string(threads));
  std::filesystem::create_directories(run.directory);
  run.status =
      run_cli(replaced(arguments, "RUN", run.directory) + " --threads " + std::to_string(threads),
              &run.output);
  // Durations differ from run to run.
  run.output = std::regex_replace(replaced(run.output, run.directory, "RUN"),
                                  std::regex("done in [0-9.]+s"), "done in Ts");
  return run;
}

// The run record without its timings, which no two runs share.
// The record without what differs from run to run: the times, and the
// provenance (the date, and the command line that names --threads).
nlohmann::json record_without_timing(const std::string& loops_csv) {
  nlohmann::json record = nlohmann::json::parse(read_text(loops_csv + ".run.json"));
  EXPECT_TRUE(record.contains("timing_ms"));
  EXPECT_TRUE(record.contains("provenance"));
  record.erase("timing_ms");
  record.erase("provenance");
  return record;
}

std::string report_without_timing(const std::string& directory) {
  const std::string html = read_text(directory + "/index.html");
  EXPECT_NE(html.find("<table id='timing'>"), std::string::npos);
  EXPECT_NE(html.find("<p class='provenance' id='provenance'>"), std::string::npos);
  return std::regex_replace(
      html,
      std::regex("<table id='timing'>.*?</table>|<p class='provenance' id='provenance'>.*?</p>"),
      "");
}

// The corridor's 84 frames as a list whose frame 30 is cut to half its bytes.
std::string list_with_a_truncated_jpeg(const TempDir& dir) {
  std::vector<std::uint8_t> bytes = test::read_file(samples_folder() + "/30.jpg");
  bytes.resize(bytes.size() / 2);
  test::write_file(dir.file("30.jpg"), bytes);
  const std::string list = dir.file("damaged.txt");
  std::ofstream out(list);
  for (int i = 1; i <= 84; ++i)
    out << (i == 30 ? dir.file("30.jpg") : samples_folder() + "/" + std::to_string(i) + ".jpg")
        << "\n";
  return list;
}

TEST(CliThreads, DetectLoopsWritesAndPrintsWhatOneThreadDoes) {
  TempDir dir;
  const std::string arguments =
      "detect-loops --report RUN/report --save-state RUN/state.bbls "
      "-o RUN/loops.csv '" +
      samples_folder() + "'";
  const CliRun one = run_in(dir, 1, arguments);
  ASSERT_EQ(one.status, 0) << one.output;
  EXPECT_NE(one.output.find("84 frames, "), std::string::npos) << one.output;
  const std::string loops = read_text(one.directory + "/loops.csv");
  ASSERT_GT(std::count(loops.begin(), loops.end(), '\n'), 5) << "too few loops to compare";
  for (const unsigned threads : {2u, 4u}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    const CliRun many = run_in(dir, threads, arguments);
    ASSERT_EQ(many.status, 0) << many.output;
    EXPECT_EQ(many.output, one.output);
    EXPECT_EQ(read_text(many.directory + "/loops.csv"), loops);
    EXPECT_EQ(record_without_timing(many.directory + "/loops.csv"),
              record_without_timing(one.directory + "/loops.csv"));
    EXPECT_EQ(report_without_timing(many.directory + "/report"),
              report_without_timing(one.directory + "/report"));
    EXPECT_EQ(test::read_file(many.directory + "/state.bbls"),
              test::read_file(one.directory + "/state.bbls"));
  }
}

TEST(CliThreads, AnUnreadableFrameStopsOrIsSkippedAsWithOneThread) {
  TempDir dir;
  const std::string list = list_with_a_truncated_jpeg(dir);
  for (const std::string& arguments :
       {"detect-loops -o RUN/loops.csv '" + list + "'",
        "detect-loops --skip-unreadable -o RUN/loops.csv '" + list + "'",
        "db build -o RUN/d.bbdb '" + list + "'",
        "db build --skip-unreadable -o RUN/d.bbdb '" + list + "'"}) {
    SCOPED_TRACE(arguments);
    const CliRun one = run_in(dir, 1, arguments);
    EXPECT_NE(one.output.find(dir.file("30.jpg") + ": damaged JPEG"), std::string::npos)
        << one.output;
    const CliRun many = run_in(dir, 4, arguments);
    EXPECT_EQ(many.status, one.status);
    EXPECT_EQ(many.output, one.output);
  }
}

TEST(CliThreads, DatabasesAndQueriesAreOneThreads) {
  TempDir dir;
  const std::string vocabulary = shared_data("kimera-small-voc/small_voc.yml.gz");
  const std::string folder = samples_folder();
  std::vector<std::uint8_t> database, journal;  // built, then added to
  std::string query;
  for (const unsigned threads : {1u, 3u}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    const CliRun build =
        run_in(dir, threads,
               "db build --vocab '" + vocabulary + "' -o RUN/d.bbdb --stride 2 '" + folder + "'");
    ASSERT_EQ(build.status, 0) << build.output;
    const CliRun add = run_in(
        dir, threads,
        "db add RUN/d.bbdb '" + folder + "/1.jpg' '" + folder + "/3.jpg' '" + folder + "/54.jpg'");
    ASSERT_EQ(add.status, 0) << add.output;
    EXPECT_NE(add.output.find("3 entries added, 45 entries"), std::string::npos) << add.output;
    const CliRun queried = run_in(dir, threads, "db query --top 4 RUN/d.bbdb '" + folder + "'");
    ASSERT_EQ(queried.status, 0) << queried.output;
    if (threads == 1) {
      database = test::read_file(build.directory + "/d.bbdb");
      journal = test::read_file(build.directory + "/d.bbdb.journal");
      query = queried.output;
      ASSERT_FALSE(database.empty());
      ASSERT_FALSE(journal.empty());
    } else {
      EXPECT_EQ(test::read_file(build.directory + "/d.bbdb"), database);
      EXPECT_EQ(test::read_file(build.directory + "/d.bbdb.journal"), journal);
      EXPECT_EQ(queried.output, query);
    }
  }
}

TEST(CliThreads, EveryFrameReadingCommandTakesThem) {
  for (const std::string command : {"detect-loops", "db build", "db query", "db add", "bench"}) {
    std::string output;
    ASSERT_EQ(run_cli(command + " --help", &output), 0) << command << "\n" << output;
    EXPECT_NE(output.find("--threads"), std::string::npos) << command << "\n" << output;
  }
  std::string output;
  EXPECT_EQ(run_cli("detect-loops --threads 257 -o x.csv '" + samples_folder() + "'", &output), 1)
      << output;
  EXPECT_NE(output.find("--threads"), std::string::npos) << output;
}

}  // namespace
}  // namespace binbow
