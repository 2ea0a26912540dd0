// The CLI's conventions for scripts: `-o -` writes the output to stdout and
// nothing else goes there; --json prints one object on stdout; --quiet
// silences progress and informational lines; results go to stdout and
// diagnostics to stderr; the help says what -o does with missing folders.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "support/test_support.h"

namespace binbow {
namespace {

using test::run_cli;
using test::run_command;
using test::TempDir;

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string quoted(const std::string& path) {
  return "'" + path + "'";
}

// Runs the CLI with stdout and stderr kept apart, in `dir`'s files.
struct Streams {
  int status = -1;
  std::string out, err;
};

Streams run_split(const TempDir& dir, const std::string& arguments) {
  Streams streams;
  std::string ignored;
  const std::string out = dir.file("stdout"), err = dir.file("stderr");
  // In `dir`, where a wrong "-" file would land; in braces: run_command
  // sends the group's stderr to its output, not ours.
  streams.status = run_command("{ cd " + quoted(dir.path()) + " && '" + test::cli_path() + "' " +
                                   arguments + " >" + quoted(out) + " 2>" + quoted(err) + "; }",
                               &ignored);
  streams.out = read_text(out);
  streams.err = read_text(err);
  return streams;
}

std::string version() {
  std::string output;
  EXPECT_EQ(run_cli("--version", &output), 0);
  EXPECT_EQ(output.rfind("binbow ", 0), 0u) << output;
  return output.substr(7, output.find('\n') - 7);
}

// One JSON object, whatever the stream holds; a test failure if it is not.
nlohmann::json parsed(const std::string& text) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    ADD_FAILURE() << "not one JSON object (" << e.what() << "):\n" << text;
    return nlohmann::json::object();
  }
}

const std::string& ground_truth() {
  static const std::string path = test::source_path("data/samples/rtabmap/samples_GT.bmp");
  return path;
}

TEST(CliScriptConventions, DetectLoopsToStdoutWritesTheFileAloneThere) {
  TempDir dir;
  const std::string frames = test::write_frame_list(dir, 30);
  const Streams to_file = run_split(
      dir, "detect-loops --threads 1 -o " + quoted(dir.file("loops.csv")) + " " + quoted(frames));
  ASSERT_EQ(to_file.status, 0) << to_file.err;
  // The summary is a result: on stdout, beside a file.
  EXPECT_NE(to_file.out.find("frames by status:\n"), std::string::npos) << to_file.out;
  EXPECT_EQ(to_file.err.find("frames by status:"), std::string::npos) << to_file.err;

  const Streams to_stdout =
      run_split(dir, "detect-loops --threads 1 -o - " + quoted(frames) + " --timing");
  ASSERT_EQ(to_stdout.status, 0) << to_stdout.err;
  EXPECT_EQ(to_stdout.out, read_text(dir.file("loops.csv")));
  EXPECT_EQ(to_stdout.out.rfind("query_index,match_index,", 0), 0u) << to_stdout.out;
  // The summary and the timing table went to stderr; no file "-", no record.
  EXPECT_NE(to_stdout.err.find("30 frames, "), std::string::npos) << to_stdout.err;
  EXPECT_NE(to_stdout.err.find("frames by status:\n"), std::string::npos) << to_stdout.err;
  EXPECT_NE(to_stdout.err.find("features"), std::string::npos) << "--timing's table";
  EXPECT_FALSE(std::filesystem::exists(dir.file("-")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("-.run.json")));
}

TEST(CliScriptConventions, ConvertToStdoutEqualsTheFile) {
  TempDir dir;
  // A vocabulary that records its extractor, so that .bbw to .bbw copies it.
  test::hand_made_vocabulary().with_descriptor("orb").save(dir.file("v.bbw"));
  for (const std::string& to : {std::string("orbslam-text"), std::string("bbw")}) {
    SCOPED_TRACE(to);
    const Streams to_file = run_split(dir, "convert --to " + to + " " + quoted(dir.file("v.bbw")) +
                                               " " + quoted(dir.file("out")));
    ASSERT_EQ(to_file.status, 0) << to_file.err;
    EXPECT_NE(to_file.out.find("wrote "), std::string::npos) << to_file.out;
    const Streams to_stdout =
        run_split(dir, "convert --to " + to + " " + quoted(dir.file("v.bbw")) + " -");
    ASSERT_EQ(to_stdout.status, 0) << to_stdout.err;
    EXPECT_EQ(to_stdout.out, read_text(dir.file("out")));
    EXPECT_NE(to_stdout.err.find("wrote -"), std::string::npos) << to_stdout.err;
  }
  // Without --to, "-" is written as .bbw.
  const Streams plain = run_split(dir, "convert " + quoted(dir.file("v.bbw")) + " -");
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_EQ(plain.out, read_text(dir.file("v.bbw")));
}

TEST(CliScriptConventions, VocabulariesAndDatabasesToStdoutEqualTheFiles) {
  TempDir dir;
  const std::string frames = quoted(test::write_frame_list(dir, 20));
  for (const auto& [command, file] :
       {std::pair<std::string, std::string>{"build-vocab --branching 3 --levels 2 --threads 1",
                                            "v.bbw"},
        {"db build --threads 1", "d.bbdb"}}) {
    SCOPED_TRACE(command);
    const Streams to_file = run_split(dir, command + " -o " + file + " " + frames);
    ASSERT_EQ(to_file.status, 0) << to_file.err;
    const Streams to_stdout = run_split(dir, command + " -o - " + frames);
    ASSERT_EQ(to_stdout.status, 0) << to_stdout.err;
    EXPECT_EQ(to_stdout.out, read_text(dir.file(file)));
    EXPECT_NE(to_stdout.err.find("-: "), std::string::npos) << "the summary: " << to_stdout.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("-")));
  }
}

TEST(CliScriptConventions, DashIsRefusedWhereTheOutputIsAFolderOrASecondStream) {
  TempDir dir;
  const std::string frames = test::write_frame_list(dir, 3);
  const Streams folder = run_split(dir, "detect-loops -o l.csv --report - " + quoted(frames));
  EXPECT_EQ(folder.status, 1);
  EXPECT_NE(folder.err.find("binbow: error: --report -: this output is a folder of files, which "
                            "cannot go to standard output"),
            std::string::npos)
      << folder.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("-")));
  const Streams state = run_split(dir, "detect-loops -o - --save-state - " + quoted(frames));
  EXPECT_EQ(state.status, 1);
  EXPECT_NE(state.err.find("--save-state -: only one output can go to standard output"),
            std::string::npos)
      << state.err;
  EXPECT_EQ(state.out, "");
  const Streams json = run_split(dir, "detect-loops -o - --json " + quoted(frames));
  EXPECT_EQ(json.status, 1);
  EXPECT_NE(json.err.find("--json and -o - both write to standard output"), std::string::npos)
      << json.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("-")));
}

TEST(CliScriptConventions, HelpSaysWhatOutputsDoWithMissingFolders) {
  for (const std::string command :
       {"detect-loops", "build-vocab", "db build", "convert", "evaluate", "make-route"}) {
    SCOPED_TRACE(command);
    std::string help;
    ASSERT_EQ(run_cli(command + " --help", &help), 0) << help;
    const bool folder = command == "evaluate" || command == "make-route";
    EXPECT_NE(
        help.find(folder ? "created with its missing parents" : "missing folders are created"),
        std::string::npos)
        << help;
    if (!folder) {
      EXPECT_NE(help.find("- writes to standard output"), std::string::npos) << help;
    }
    EXPECT_NE(help.find("--quiet"), std::string::npos) << help;
  }
}

TEST(CliScriptConventions, DetectLoopsAndEvaluateJson) {
  TempDir dir;
  const std::string loops = dir.file("loops.csv");
  const Streams detect = run_split(dir, "detect-loops --json --timing -o " + quoted(loops) + " " +
                                            quoted(test::samples_folder()));
  ASSERT_EQ(detect.status, 0) << detect.err;
  const nlohmann::json summary = parsed(detect.out);
  EXPECT_EQ(summary.value("binbow_version", ""), version());
  EXPECT_EQ(summary.value("loops_csv", ""), loops);
  EXPECT_EQ(summary.value("run_record", ""), loops + ".run.json");
  EXPECT_EQ(summary.value("frames", 0), 84);
  EXPECT_GT(summary.value("loops", 0), 10);
  ASSERT_TRUE(summary.contains("frames_by_status")) << summary;
  EXPECT_EQ(summary["frames_by_status"].value("loop-detected", -1), summary.value("loops", 0));
  EXPECT_EQ(summary.value("frequency_hz", 0.0), 1.0);
  EXPECT_TRUE(summary["report"].is_null());
  ASSERT_TRUE(summary["timing"].is_array());
  EXPECT_EQ(summary["timing"][0].value("stage", ""), "features");
  // The human-readable summary went to stderr.
  EXPECT_NE(detect.err.find("frames by status:"), std::string::npos) << detect.err;

  const Streams evaluate =
      run_split(dir, "evaluate --json --gt " + quoted(ground_truth()) + " " + quoted(loops));
  ASSERT_EQ(evaluate.status, 0) << evaluate.err;
  const nlohmann::json result = parsed(evaluate.out);
  EXPECT_EQ(result.value("binbow_version", ""), version());
  EXPECT_EQ(result.value("detections", -1), summary.value("loops", 0));
  EXPECT_EQ(result.value("precision", 0.0), 1.0);
  EXPECT_GT(result.value("recall", 0.0), 0.5);
  EXPECT_EQ(result.value("queries_with_loops", 0), 44);
  ASSERT_TRUE(result["missed_loops"].is_array());
  EXPECT_EQ(result["missed_loops"].size(),
            result.value("queries_with_loops", 0u) - result.value("queries_found", 0u));
  EXPECT_EQ(result.value("run_record", ""), loops + ".run.json");
  EXPECT_FALSE(result.contains("sweep"));

  // The curve without re-running detection: the scores thresholded.
  std::filesystem::remove(loops + ".run.json");
  const Streams sweep = run_split(
      dir, "evaluate --json --sweep --gt " + quoted(ground_truth()) + " " + quoted(loops));
  ASSERT_EQ(sweep.status, 0) << sweep.err;
  const nlohmann::json swept = parsed(sweep.out);
  ASSERT_TRUE(swept.contains("sweep")) << swept;
  EXPECT_EQ(swept["sweep"].value("parameter", ""), "score");
  EXPECT_GT(swept["sweep"]["curve"].size(), 2u);
  EXPECT_EQ(swept["sweep"].value("recall_at_full_precision", -1.0), result.value("recall", 0.0));
}

TEST(CliScriptConventions, DbQueryAndInfoJson) {
  TempDir dir;
  const std::string database = dir.file("db.bbdb");
  const std::string frames = test::write_frame_list(dir, 12);
  ASSERT_EQ(
      run_split(dir, "db build --threads 1 -o " + quoted(database) + " " + quoted(frames)).status,
      0);
  const std::string folder = test::samples_folder();
  const Streams query =
      run_split(dir, "db query --json --top 2 " + quoted(database) + " " +
                         quoted(folder + "/5.jpg") + " " + quoted(folder + "/9.jpg"));
  ASSERT_EQ(query.status, 0) << query.err;
  const nlohmann::json results = parsed(query.out);
  EXPECT_EQ(results.value("binbow_version", ""), version());
  EXPECT_EQ(results.value("top", 0), 2);
  ASSERT_EQ(results["queries"].size(), 2u) << results;
  const nlohmann::json& first = results["queries"][0];
  EXPECT_EQ(first.value("query", ""), folder + "/5.jpg");
  ASSERT_EQ(first["results"].size(), 2u);
  EXPECT_EQ(first["results"][0].value("rank", 0), 1);
  EXPECT_EQ(first["results"][0].value("entry", -1), 4);  // the frame itself
  EXPECT_EQ(first["results"][0].value("file", ""), folder + "/5.jpg");
  EXPECT_GT(first["results"][0].value("score", 0.0), first["results"][1].value("score", 1.0));

  const Streams info = run_split(dir, "info --json " + quoted(database));
  ASSERT_EQ(info.status, 0) << info.err;
  const nlohmann::json fields = parsed(info.out);
  EXPECT_EQ(fields.value("binbow_version", ""), version());
  EXPECT_EQ(fields.value("kind", ""), "database");
  EXPECT_EQ(fields.value("entries", 0), 12);
  EXPECT_EQ(fields.value("vocabulary_included", ""), "yes");
  // The same fields as the lines, numbers as numbers.
  const Streams lines = run_split(dir, "info " + quoted(database));
  EXPECT_NE(lines.out.find("entries: 12\n"), std::string::npos) << lines.out;

  const Streams system = run_split(dir, "info --system --json");
  ASSERT_EQ(system.status, 0) << system.err;
  EXPECT_FALSE(parsed(system.out).value("hamming_kernel", "").empty()) << system.out;
}

TEST(CliScriptConventions, QuietLeavesResultsWarningsAndErrorsAlone) {
  TempDir dir;
  const std::string frames = test::write_frame_list(dir, 3);
  const std::string loops = dir.file("loops.csv");
  // Before or after the command's name; detect-loops' result is its file.
  for (const std::string command : {"--quiet detect-loops", "detect-loops -q"}) {
    SCOPED_TRACE(command);
    const Streams quiet =
        run_split(dir, command + " --threads 1 -o " + quoted(loops) + " --report " +
                           quoted(dir.file("report")) + " " + quoted(frames));
    ASSERT_EQ(quiet.status, 0) << quiet.err;
    EXPECT_EQ(quiet.out, "");
    // Three frames can have no candidate: the warning stays, nothing else.
    EXPECT_EQ(quiet.err.rfind("binbow: warning: ", 0), 0u) << quiet.err;
    EXPECT_EQ(quiet.err.find('\n'), quiet.err.size() - 1) << quiet.err;
  }
  const Streams loud =
      run_split(dir, "detect-loops --threads 1 -o " + quoted(loops) + " " + quoted(frames));
  EXPECT_NE(loud.err.find("detecting loops: 3 done"), std::string::npos) << loud.err;

  // A result asked for still prints; an error still says why.
  const Streams evaluate =
      run_split(dir, "evaluate -q --gt " + quoted(ground_truth()) + " " + quoted(loops));
  ASSERT_EQ(evaluate.status, 0) << evaluate.err;
  EXPECT_NE(evaluate.out.find("precision: "), std::string::npos) << evaluate.out;
  EXPECT_EQ(evaluate.err, "");
  const Streams json =
      run_split(dir, "--quiet detect-loops --json -o " + quoted(loops) + " " + quoted(frames));
  EXPECT_EQ(parsed(json.out).value("frames", 0), 3);
  const Streams failed = run_split(dir, "info -q " + quoted(dir.file("missing.bbw")));
  EXPECT_EQ(failed.status, 1);
  EXPECT_EQ(failed.err.rfind("binbow: error: ", 0), 0u) << failed.err;
}

TEST(CliScriptConventions, RunRecordAndReportsSayWhoWroteThemWhenAndHow) {
  TempDir dir;
  const std::string loops = dir.file("it's loops.csv");
  const std::string frames = test::write_frame_list(dir, 30);
  const std::string arguments = "detect-loops --threads 1 -o \"" + loops + "\" --report " +
                                quoted(dir.file("detected")) + " " + quoted(frames);
  const Streams detect = run_split(dir, arguments);
  ASSERT_EQ(detect.status, 0) << detect.err;
  const nlohmann::json record = parsed(read_text(loops + ".run.json"));
  ASSERT_TRUE(record.contains("provenance")) << record.dump().substr(0, 400);
  const nlohmann::json& provenance = record["provenance"];
  EXPECT_EQ(provenance.value("binbow_version", ""), version());
  EXPECT_TRUE(std::regex_match(provenance.value("date", ""),
                               std::regex("20[0-9]{2}-[01][0-9]-[0-3][0-9]T[0-2][0-9]:[0-5][0-9]:"
                                          "[0-6][0-9]Z")))
      << provenance;
  // The command line as a shell reads it back: the quote in the name escaped.
  const std::string command = provenance.value("command", "");
  EXPECT_NE(command.find(" detect-loops --threads 1 -o '" + dir.path() + "/it'\\''s loops.csv' "),
            std::string::npos)
      << command;
  std::string echoed;
  ASSERT_EQ(run_command("printf '%s|' " + command.substr(command.find(" detect-loops")), &echoed),
            0);
  EXPECT_NE(echoed.find("|-o|" + loops + "|"), std::string::npos) << echoed;

  const std::string page = read_text(dir.file("detected/index.html"));
  EXPECT_NE(page.find("<p class='provenance' id='provenance'>Written by binbow " + version() +
                      " on " + provenance.value("date", "")),
            std::string::npos)
      << page.substr(0, 3000);
  EXPECT_NE(page.find("detect-loops --threads 1 -o"), std::string::npos);

  // evaluate's report: its own line, and the detection run's from the record.
  const Streams evaluate =
      run_split(dir, "evaluate --report " + quoted(dir.file("evaluated")) + " --gt " +
                         quoted(ground_truth()) + " \"" + loops + "\"");
  ASSERT_EQ(evaluate.status, 0) << evaluate.err;
  const std::string judged = read_text(dir.file("evaluated/index.html"));
  EXPECT_NE(judged.find("id='provenance'>Written by binbow " + version()), std::string::npos);
  EXPECT_NE(judged.find(" evaluate --report "), std::string::npos);
  EXPECT_NE(judged.find("id='run-provenance'>Loops detected by binbow " + version() + " on " +
                        provenance.value("date", "")),
            std::string::npos)
      << judged.substr(0, 3000);
}

}  // namespace
}  // namespace binbow
