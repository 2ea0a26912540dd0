// `binbow detect-loops` on videos (the image-source options, the loop
// detector's frequency from the frames processed per second, the report's
// pictures of video frames), its summary of frame statuses and the warning
// when no frame can have a candidate, --skip-unreadable; `binbow features` on
// a video.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <regex>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "binbow/loop/evaluation.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::run_cli;
using test::samples_folder;
using test::shared_data;
using test::TempDir;

// The 84 frames of the corridor walked twice as a 4 fps MJPG video.
std::string write_corridor_video(const TempDir& dir) {
  const std::string path = dir.file("corridor.avi");
  cv::VideoWriter writer;
  for (int i = 1; i <= 84; ++i) {
    const cv::Mat frame = cv::imread(samples_folder() + "/" + std::to_string(i) + ".jpg");
    EXPECT_FALSE(frame.empty()) << "frame " << i;
    if (!writer.isOpened()) {
      writer.open(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 4, frame.size(), true);
      EXPECT_TRUE(writer.isOpened()) << "OpenCV cannot write MJPG .avi";
    }
    writer.write(frame);
  }
  writer.release();
  return path;
}

nlohmann::json run_record(const std::string& loops_csv) {
  std::ifstream in(loops_csv + ".run.json");
  EXPECT_TRUE(in.good()) << "no run record beside " << loops_csv;
  return nlohmann::json::parse(in);
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::size_t count_of(const std::string& text, const std::string& needle) {
  std::size_t count = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos;
       at = text.find(needle, at + needle.size()))
    ++count;
  return count;
}

TEST(CliDetectLoops, VideoFramesPerSecondSetTheFrequencyUnlessParamsDo) {
  TempDir dir;
  const std::string video = write_corridor_video(dir);
  const std::string loops = dir.file("loops.csv");
  std::string output;
  // The README's tour line: 4 fps sampled at 2, so 42 frames at 2 Hz.
  ASSERT_EQ(run_cli("detect-loops --descriptor brief -o '" + loops + "' '" + video +
                        "' --video-fps 2 --max-width 320",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("42 frames, "), std::string::npos) << output;
  EXPECT_NE(output.find("frequency: 2 Hz (video frames processed per second)\n"), std::string::npos)
      << output;
  nlohmann::json record = run_record(loops);
  EXPECT_EQ(record["params"]["frequency"], 2.0);
  EXPECT_EQ(record["params"]["dislocal"], 40);
  EXPECT_EQ(record["params"]["max_db_results"], 100);
  EXPECT_EQ(record["source"]["video_fps"], 2.0);
  EXPECT_EQ(record["source"]["max_width"], 320);
  EXPECT_EQ(record["frames"][41]["file"], video + "#82");

  // --stride divides the rate too; --params keys win, the others follow it.
  write_text(dir.file("k.json"), R"({"k": 2})");
  ASSERT_EQ(run_cli("detect-loops -o '" + loops + "' '" + video + "' --stride 4 --params '" +
                        dir.file("k.json") + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("21 frames, "), std::string::npos) << output;
  EXPECT_NE(output.find("frequency: 1 Hz (video frames processed per second)\n"), std::string::npos)
      << output;
  record = run_record(loops);
  EXPECT_EQ(record["params"]["k"], 2);
  EXPECT_EQ(record["params"]["dislocal"], 20);
  write_text(dir.file("f.json"), R"({"frequency": 0.5, "dislocal": 3})");
  ASSERT_EQ(run_cli("detect-loops -o '" + loops + "' '" + video + "' --params '" +
                        dir.file("f.json") + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("frequency: 0.5 Hz (--params)\n"), std::string::npos) << output;
  record = run_record(loops);
  EXPECT_EQ(record["params"]["dislocal"], 3);
  EXPECT_EQ(record["params"]["max_db_results"], 25);

  // Images have no frame rate: the paper's 1 Hz defaults.
  ASSERT_EQ(
      run_cli("detect-loops -o '" + loops + "' '" + test::write_frame_list(dir, 30) + "'", &output),
      0)
      << output;
  EXPECT_NE(output.find("frequency: 1 Hz (the paper's default; images have no frame rate)\n"),
            std::string::npos)
      << output;
  EXPECT_EQ(run_record(loops)["params"]["dislocal"], 20);
}

// evaluate --sweep re-reads the inputs as detect-loops read them.
TEST(CliDetectLoops, SweepOfASampledRunReadsTheSameFrames) {
  TempDir dir;
  const std::string loops = dir.file("loops.csv");
  std::string output;
  ASSERT_EQ(
      run_cli("detect-loops -o '" + loops + "' '" + samples_folder() + "' --stride 2", &output), 0)
      << output;
  EXPECT_NE(output.find("42 frames, "), std::string::npos) << output;
  EXPECT_EQ(run_cli("evaluate --sweep --gt '" + shared_data("rtabmap-samples/samples_GT.bmp") +
                        "' '" + loops + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("recall at 100% precision:"), std::string::npos) << output;
}

TEST(CliDetectLoops, ReportOfAVideoRunShowsItsFrames) {
  TempDir dir;
  const std::string video = write_corridor_video(dir);
  write_text(dir.file("p.json"), R"({"dislocal": 20})");
  std::string output;
  ASSERT_EQ(
      run_cli("detect-loops --max-width 320 --params '" + dir.file("p.json") + "' -o '" +
                  dir.file("loops.csv") + "' --report '" + dir.file("report") + "' '" + video + "'",
              &output),
      0)
      << output;
  EXPECT_EQ(output.find("imread"), std::string::npos) << output;
  std::smatch loops;
  ASSERT_TRUE(std::regex_search(output, loops, std::regex("84 frames, ([0-9]+) loops"))) << output;
  const int detected = std::stoi(loops[1]);
  ASSERT_GT(detected, 10) << output;
  std::ifstream in(dir.file("report/index.html"));
  const std::string page((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(page.find("not readable"), std::string::npos);
  EXPECT_EQ(count_of(page, "src='data:image/jpeg;base64,"), static_cast<std::size_t>(detected));
  EXPECT_NE(page.find(video + "#"), std::string::npos);
}

TEST(CliDetectLoops, OnlineVocabularyIsRecordedReRunByTheSweepAndExportedForLaterRuns) {
  TempDir dir;
  const std::string loops = dir.file("loops.csv");
  const std::string exported = dir.file("grown.bbw");
  std::string output;
  ASSERT_EQ(run_cli("detect-loops --online-vocabulary --save-vocabulary '" + exported + "' -o '" +
                        loops + "' '" + samples_folder() + "'",
                    &output),
            0)
      << output;
  const nlohmann::json record = run_record(loops);
  EXPECT_EQ(record.at("online_vocabulary"), true);
  EXPECT_EQ(record.at("vocabulary"), "");
  std::ifstream csv(loops);
  const std::string detected((std::istreambuf_iterator<char>(csv)), {});

  // The sweep re-runs detection with an online vocabulary too: at the
  // recorded alpha it finds what the run found.
  ASSERT_EQ(run_cli("evaluate --gt '" + shared_data("rtabmap-samples/samples_GT.bmp") +
                        "' --sweep --sweep-values 0.3 '" + loops + "'",
                    &output),
            0)
      << output;
  std::smatch recall;
  ASSERT_TRUE(std::regex_search(output, recall, std::regex("\nrecall: ([0-9.]+)"))) << output;
  EXPECT_NE(output.find("recall at 100% precision: " + recall[1].str()), std::string::npos)
      << output;

  // Same input, same loops.
  ASSERT_EQ(run_cli("detect-loops --online-vocabulary -o '" + dir.file("again.csv") + "' '" +
                        samples_folder() + "'",
                    &output),
            0)
      << output;
  std::ifstream again_csv(dir.file("again.csv"));
  EXPECT_EQ(std::string((std::istreambuf_iterator<char>(again_csv)), {}), detected);

  // The exported words serve as a fixed vocabulary.
  ASSERT_EQ(run_cli("detect-loops --vocab '" + exported + "' -o '" + dir.file("fixed.csv") + "' '" +
                        samples_folder() + "'",
                    &output),
            0)
      << output;
}

TEST(CliDetectLoops, OnlineVocabularyUsageErrors) {
  TempDir dir;
  std::string output;
  EXPECT_EQ(run_cli("detect-loops --online-vocabulary --vocab x.bbw -o '" + dir.file("l.csv") +
                        "' '" + samples_folder() + "'",
                    &output),
            1);
  EXPECT_NE(output.find("--vocab excludes --online-vocabulary"), std::string::npos) << output;
  EXPECT_EQ(run_cli("detect-loops --save-vocabulary '" + dir.file("v.bbw") + "' -o '" +
                        dir.file("l.csv") + "' '" + samples_folder() + "'",
                    &output),
            1);
  EXPECT_NE(output.find("--save-vocabulary requires --online-vocabulary"), std::string::npos)
      << output;
  EXPECT_FALSE(std::ifstream(dir.file("l.csv")).good());
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// Frames [first, last] of the corridor as a list file.
std::string write_frame_range(const TempDir& dir, const std::string& name, int first, int last) {
  const std::string path = dir.file(name);
  std::ofstream list(path);
  for (int i = first; i <= last; ++i) list << samples_folder() << "/" << i << ".jpg\n";
  return path;
}

// --save-state after frames 1..42, --resume-state for 43..84: the loops of
// the two runs are the uninterrupted run's, numbered and named alike (the
// second run's matches are frames of the first).
TEST(CliDetectLoops, SaveStateThenResumeStateEqualsOneRun) {
  TempDir dir;
  const std::string first = write_frame_range(dir, "first.txt", 1, 42);
  const std::string second = write_frame_range(dir, "second.txt", 43, 84);
  const std::string all = write_frame_range(dir, "all.txt", 1, 84);
  for (const std::string kind : {"fixed", "online"}) {
    SCOPED_TRACE(kind);
    const std::string vocabulary = kind == "online" ? " --online-vocabulary" : "";
    const std::string state = dir.file(kind + ".bbld");
    std::string output;
    ASSERT_EQ(run_cli("detect-loops" + vocabulary + (kind == "online" ? " --exact" : "") + " -o '" +
                          dir.file("all.csv") + "' '" + all + "'",
                      &output),
              0)
        << output;
    ASSERT_EQ(run_cli("detect-loops" + vocabulary + (kind == "online" ? " --exact" : "") +
                          " --save-state '" + state + "' -o '" + dir.file("first.csv") + "' '" +
                          first + "'",
                      &output),
              0)
        << output;
    EXPECT_NE(output.find("state: 42 frames -> " + state), std::string::npos) << output;
    ASSERT_EQ(run_cli("info '" + state + "'", &output), 0) << output;
    EXPECT_NE(output.find("kind: loop detector state\n"), std::string::npos) << output;
    EXPECT_NE(output.find("vocabulary: " + kind + "\n"), std::string::npos) << output;
    EXPECT_NE(output.find("frames: 42\n"), std::string::npos) << output;
    // Neither the kind nor the descriptor needs repeating.
    ASSERT_EQ(run_cli("detect-loops --resume-state '" + state + "' -o '" + dir.file("second.csv") +
                          "' '" + second + "'",
                      &output),
              0)
        << output;
    EXPECT_NE(output.find("resuming after 42 frames"), std::string::npos) << output;
    const std::string one_run = read_text(dir.file("all.csv"));
    const std::string first_run = read_text(dir.file("first.csv"));
    const std::string second_run = read_text(dir.file("second.csv"));
    const std::string header = one_run.substr(0, one_run.find('\n') + 1);
    EXPECT_GT(std::count(second_run.begin(), second_run.end(), '\n'), 20);
    EXPECT_EQ(first_run + second_run.substr(header.size()), one_run);
    const nlohmann::json record = run_record(dir.file("second.csv"));
    EXPECT_EQ(record.at("resumed_frames"), 42);
    EXPECT_EQ(record.value("online_vocabulary", false), kind == "online");
    // Its indices are the whole sequence's: evaluated against the whole
    // ground truth from loops.csv alone (the record cannot re-run it).
    ASSERT_EQ(run_cli("evaluate --sweep --gt '" + shared_data("rtabmap-samples/samples_GT.bmp") +
                          "' '" + dir.file("second.csv") + "'",
                      &output),
              0)
        << output;
    EXPECT_NE(output.find("resumed from"), std::string::npos) << output;
    EXPECT_NE(output.find("false positives: 0"), std::string::npos) << output;
  }
}

TEST(CliDetectLoops, ResumeStateUsageErrors) {
  TempDir dir;
  const std::string frames = test::write_frame_list(dir, 3);
  const std::string fixed = dir.file("fixed.bbld");
  const std::string online = dir.file("online.bbld");
  std::string output;
  ASSERT_EQ(run_cli("detect-loops --save-state '" + fixed + "' -o '" + dir.file("a.csv") + "' '" +
                        frames + "'",
                    &output),
            0)
      << output;
  ASSERT_EQ(run_cli("detect-loops --online-vocabulary --descriptor brief --save-state '" + online +
                        "' -o '" + dir.file("b.csv") + "' '" + frames + "'",
                    &output),
            0)
      << output;
  const auto expect_usage_error = [&](const std::string& arguments, const std::string& message) {
    EXPECT_EQ(
        run_cli("detect-loops " + arguments + " -o '" + dir.file("l.csv") + "' '" + frames + "'",
                &output),
        1)
        << arguments;
    EXPECT_NE(output.find(message), std::string::npos) << output;
    EXPECT_NE(output.find("for usage"), std::string::npos) << output;
  };
  expect_usage_error("--resume-state '" + fixed + "' --online-vocabulary",
                     "holds a fixed vocabulary's state; --online-vocabulary conflicts with it");
  expect_usage_error("--resume-state '" + online + "' --vocab x.bbw",
                     "holds an online vocabulary's state; --vocab conflicts with it");
  expect_usage_error("--resume-state '" + online + "' --descriptor orb",
                     "was run with brief descriptors; --descriptor orb conflicts with it");
  expect_usage_error("--resume-state '" + fixed + "' --params p.json",
                     "--params excludes --resume-state");
  expect_usage_error("--resume-state '" + online + "' --online-vocabulary --trees 2",
                     "--trees excludes --resume-state");
  for (const std::string option :
       {"--new-word-distance 0.2", "--purge-after-images 3", "--trees 2", "--branching 4",
        "--leaf-size 8", "--max-checks 9", "--exact", "--scoring l2", "--seed 3"})
    expect_usage_error(option,
                       option.substr(0, option.find(' ')) + " requires --online-vocabulary");
  EXPECT_FALSE(std::ifstream(dir.file("l.csv")).good());
  // An ORB vocabulary that is not the state's: the library's error names both.
  const std::string other = dir.file("other.bbw");
  ASSERT_EQ(run_cli("detect-loops --online-vocabulary --save-vocabulary '" + other + "' -o '" +
                        dir.file("c.csv") + "' '" + frames + "'",
                    &output),
            0)
      << output;
  EXPECT_EQ(run_cli("detect-loops --resume-state '" + fixed + "' --vocab '" + other + "' -o '" +
                        dir.file("l.csv") + "' '" + frames + "'",
                    &output),
            1);
  EXPECT_NE(output.find("different vocabulary"), std::string::npos) << output;
}

// The online vocabulary's options reach it: a stricter new-word distance
// makes more words, which --save-vocabulary's summary counts.
TEST(CliDetectLoops, OnlineVocabularyOptionsReachTheVocabulary) {
  TempDir dir;
  const std::string frames = test::write_frame_list(dir, 6);
  std::string loose, strict;
  ASSERT_EQ(run_cli("detect-loops --online-vocabulary --new-word-distance 0.4 --save-vocabulary '" +
                        dir.file("a.bbw") + "' -o '" + dir.file("a.csv") + "' '" + frames + "'",
                    &loose),
            0)
      << loose;
  ASSERT_EQ(run_cli("detect-loops --online-vocabulary --new-word-distance 0.1 --purge-after-images "
                    "0 --scoring l2 --exact --save-vocabulary '" +
                        dir.file("b.bbw") + "' -o '" + dir.file("b.csv") + "' '" + frames + "'",
                    &strict),
            0)
      << strict;
  EXPECT_GT(test::printed_number(strict, "online vocabulary"),
            test::printed_number(loose, "online vocabulary"))
      << loose << strict;
  // Recorded, so that evaluate --sweep re-runs with them.
  const nlohmann::json options = run_record(dir.file("b.csv")).at("online_options");
  EXPECT_EQ(options.at("new_word_distance"), 0.1);
  EXPECT_EQ(options.at("purge_after_images"), 0);
  EXPECT_EQ(options.at("scoring"), "l2");
  EXPECT_EQ(options.at("exact"), true);
}

TEST(CliDetectLoops, CountsFramesPerStatusAndWarnsWhenNoFrameCanHaveACandidate) {
  TempDir dir;
  const std::string list = test::write_frame_list(dir, 10);
  std::string output;
  ASSERT_EQ(run_cli("detect-loops -o '" + dir.file("loops.csv") + "' '" + list + "'", &output), 0)
      << output;
  EXPECT_NE(output.find("10 frames, 0 loops"), std::string::npos) << output;
  const std::string statuses =
      "frames by status:\n  loop-detected: 0\n  no-database-results: 10\n"
      "  low-normalisation-score: 0\n  low-scores: 0\n  no-islands: 0\n"
      "  no-temporal-consistency: 0\n  no-geometric-consistency: 0\n";
  EXPECT_NE(output.find(statuses), std::string::npos) << output;
  EXPECT_NE(output.find("binbow: warning: no frame can have a loop candidate: candidates must be "
                        "more than dislocal = 20 frames older than the query, and the sequence "
                        "has only 10 frames; set a smaller \"dislocal\" with --params"),
            std::string::npos)
      << output;

  // {"frequency": 10} makes dislocal 200 frames, longer than 84.
  write_text(dir.file("p.json"), R"({"frequency": 10})");
  ASSERT_EQ(run_cli("detect-loops --params '" + dir.file("p.json") + "' -o '" +
                        dir.file("loops.csv") + "' '" + samples_folder() + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("dislocal = 200 frames"), std::string::npos) << output;

  // Frames 21 and 22 of 23 can have candidates: no warning.
  ASSERT_EQ(run_cli("detect-loops -o '" + dir.file("loops.csv") + "' '" +
                        test::write_frame_list(dir, 23) + "'",
                    &output),
            0)
      << output;
  EXPECT_EQ(output.find("warning"), std::string::npos) << output;
  EXPECT_NE(output.find("frames by status:\n  loop-detected: 0\n"), std::string::npos) << output;
}

// The corridor's 84 frames as a list whose frame `damaged` (1-based) is a copy
// cut to half its bytes; writes the list of intact frames too.
std::vector<std::string> write_list_with_a_truncated_jpeg(const TempDir& dir, int damaged,
                                                          std::string& damaged_list,
                                                          std::string& intact_list) {
  std::vector<std::string> files;
  for (int i = 1; i <= 84; ++i)
    files.push_back(samples_folder() + "/" + std::to_string(i) + ".jpg");
  std::vector<std::uint8_t> bytes = test::read_file(files[damaged - 1]);
  bytes.resize(bytes.size() / 2);
  const std::string truncated = dir.file(std::to_string(damaged) + ".jpg");
  test::write_file(truncated, bytes);
  damaged_list = dir.file("damaged.txt");
  intact_list = dir.file("intact.txt");
  std::ofstream damaged_out(damaged_list), intact_out(intact_list);
  for (int i = 1; i <= 84; ++i) {
    intact_out << files[i - 1] << "\n";
    damaged_out << (i == damaged ? truncated : files[i - 1]) << "\n";
  }
  files[damaged - 1] = truncated;
  return files;
}

TEST(CliDetectLoops, TruncatedJpegStopsTheRunUnlessSkippedAndKeepsTheFrameNumbers) {
  TempDir dir;
  // Frame 50 lies in the corridor's second pass, where loops are found.
  constexpr int kDamaged = 50;
  std::string damaged_list, intact_list;
  const std::vector<std::string> files =
      write_list_with_a_truncated_jpeg(dir, kDamaged, damaged_list, intact_list);
  const std::string truncated = files[kDamaged - 1];
  const std::string gt = test::source_path("data/samples/rtabmap/samples_GT.bmp");

  std::string output;
  const std::string strict =
      "detect-loops -o '" + dir.file("strict.csv") + "' '" + damaged_list + "'";
  EXPECT_EQ(run_cli(strict, &output), 1) << output;
  EXPECT_NE(output.find("binbow: error: " + truncated + ": damaged JPEG"), std::string::npos)
      << output;

  ASSERT_EQ(run_cli("detect-loops --skip-unreadable -o '" + dir.file("skipped.csv") + "' '" +
                        damaged_list + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("binbow: warning: " + truncated + ": damaged JPEG"), std::string::npos)
      << output;
  EXPECT_NE(output.find("skipped frames: 1\n"), std::string::npos) << output;
  EXPECT_NE(output.find("84 frames, "), std::string::npos) << output;
  ASSERT_EQ(
      run_cli("detect-loops -o '" + dir.file("intact.csv") + "' '" + intact_list + "'", &output), 0)
      << output;
  EXPECT_EQ(output.find("skipped frames"), std::string::npos) << output;

  // The record keeps every frame at its index, the damaged one as unreadable.
  const nlohmann::json record = run_record(dir.file("skipped.csv"));
  ASSERT_EQ(record.at("frames").size(), files.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    EXPECT_EQ(record["frames"][i].at("file"), files[i]) << i;
    EXPECT_EQ(record["frames"][i].at("status") == "unreadable", i == kDamaged - 1) << i;
  }

  // Each loop's indices are its files' positions in the list: one frame fewer
  // would shift every index after the damaged frame.
  const std::vector<loop::Detection> skipped = loop::read_detections_csv(dir.file("skipped.csv"));
  const std::vector<loop::Detection> intact = loop::read_detections_csv(dir.file("intact.csv"));
  ASSERT_FALSE(skipped.empty());
  std::size_t after_damaged = 0;
  for (const loop::Detection& d : skipped) {
    ASSERT_LT(d.query, files.size());
    ASSERT_LT(d.match, files.size());
    EXPECT_EQ(d.query_file, files[d.query]);
    EXPECT_EQ(d.match_file, files[d.match]);
    EXPECT_NE(d.query, std::size_t{kDamaged - 1});
    after_damaged += d.query > kDamaged - 1;
  }
  EXPECT_GT(after_damaged, 0u) << "no loop after the damaged frame: the check shows nothing";
  // Against the ground truth the run is as precise as the intact one (a shift
  // by one frame would turn loops into false positives) and finds nearly as
  // many loops (the damaged frame's own, and the queries whose temporal
  // consistency it broke, are missed).
  std::string intact_result, skipped_result;
  ASSERT_EQ(run_cli("evaluate --gt '" + gt + "' '" + dir.file("intact.csv") + "'", &intact_result),
            0)
      << intact_result;
  ASSERT_EQ(
      run_cli("evaluate --gt '" + gt + "' '" + dir.file("skipped.csv") + "'", &skipped_result), 0)
      << skipped_result;
  EXPECT_EQ(test::printed_number(skipped_result, "precision"),
            test::printed_number(intact_result, "precision"))
      << skipped_result << intact_result;
  EXPECT_GE(test::printed_number(skipped_result, "recall"),
            test::printed_number(intact_result, "recall") - 0.1)
      << skipped_result << intact_result;
  // Frame for frame, the loops found are the intact run's (only the damaged
  // frame's own loop is lost on this sequence).
  for (const loop::Detection& d : skipped)
    EXPECT_TRUE(std::any_of(
        intact.begin(), intact.end(),
        [&](const loop::Detection& e) { return e.query == d.query && e.match == d.match; }))
        << d.query << " -> " << d.match;
  EXPECT_GE(skipped.size() + 3, intact.size());
  // The sweep re-runs the frames as the run read them: the damaged one skipped.
  ASSERT_EQ(
      run_cli("evaluate --sweep --gt '" + gt + "' '" + dir.file("skipped.csv") + "'", &output), 0)
      << output;
  EXPECT_NE(output.find("query " + std::to_string(kDamaged - 1) + ": unreadable"),
            std::string::npos)
      << output;
}

TEST(CliFeatures, ReadsTheFirstFrameOfAVideoOrFolderWithTheSourceOptions) {
  TempDir dir;
  const std::string video = write_corridor_video(dir);
  std::string output;
  ASSERT_EQ(run_cli("features '" + video + "' --max-width 320", &output), 0) << output;
  EXPECT_NE(output.find("image: " + video + "#0 (320x240)\n"), std::string::npos) << output;
  ASSERT_EQ(run_cli("features '" + samples_folder() + "'", &output), 0) << output;
  EXPECT_NE(output.find("image: " + samples_folder() + "/1.jpg (512x384)\n"), std::string::npos)
      << output;
}

// Every command that reads images takes the same image-source options.
TEST(CliImageSourceOptions, EveryImageReadingCommandTakesThem) {
  for (const std::string command :
       {"detect-loops", "db build", "db query", "db add", "build-vocab", "bench", "features"}) {
    std::string output;
    ASSERT_EQ(run_cli(command + " --help", &output), 0) << command << "\n" << output;
    for (const char* option : {"--stride", "--max-width", "--video-fps"})
      EXPECT_NE(output.find(option), std::string::npos) << command << " lacks " << option;
  }
}

}  // namespace
}  // namespace binbow
