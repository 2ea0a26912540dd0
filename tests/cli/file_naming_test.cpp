// Errors name the file they come from: a run record whose content the sweep
// cannot use, a saved state naming a descriptor binbow does not know, an
// image that exhausts memory.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "binbow/loop/loop_detector.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::run_cli;
using test::samples_folder;
using test::shared_data;
using test::TempDir;

// `binbow evaluate --sweep` on a run record changed by `change`: fails, and
// the message names the record.
void expect_sweep_error_naming_the_record(const std::string& what,
                                          void (*change)(nlohmann::json& record)) {
  SCOPED_TRACE(what);
  TempDir dir;
  const std::string loops = dir.file("loops.csv");
  const std::string record_path = loops + ".run.json";
  std::string output;
  ASSERT_EQ(
      run_cli("detect-loops -o '" + loops + "' '" + test::write_frame_list(dir, 4) + "'", &output),
      0)
      << output;
  nlohmann::json record = nlohmann::json::parse(std::ifstream(record_path));
  change(record);
  std::ofstream(record_path) << record.dump();
  EXPECT_EQ(run_cli("evaluate --sweep --gt '" + shared_data("rtabmap-samples/samples_GT.bmp") +
                        "' '" + loops + "'",
                    &output),
            1)
      << output;
  EXPECT_NE(output.find("binbow: error: " + record_path + ": "), std::string::npos) << output;
}

TEST(CliFileNaming, SweepErrorsFromTheRunRecordNameIt) {
  expect_sweep_error_naming_the_record(
      "unknown descriptor", [](nlohmann::json& r) { r["descriptor"] = "no-such-descriptor"; });
  expect_sweep_error_naming_the_record("parameters out of range",
                                       [](nlohmann::json& r) { r["params"]["k"] = -3; });
  expect_sweep_error_naming_the_record("inputs that now have fewer frames", [](nlohmann::json& r) {
    r["inputs"] = {samples_folder() + "/1.jpg", samples_folder() + "/2.jpg"};
  });
  expect_sweep_error_naming_the_record(
      "online vocabulary options out of range", [](nlohmann::json& r) {
        r["online_vocabulary"] = true;
        r["online_options"] = {
            {"new_word_distance", 0.1}, {"purge_after_images", 0}, {"trees", 0},
            {"branching", 8},           {"leaf_size", 64},         {"max_checks", 32},
            {"exact", false},           {"scoring", "l1"},         {"seed", 1}};
      });
}

TEST(CliFileNaming, AStateNamingAnUnknownOrMismatchedDescriptorIsNamed) {
  TempDir dir;
  const std::string frames = test::write_frame_list(dir, 3);
  std::string output;
  const auto expect_state_error = [&](const std::string& descriptor, std::size_t code_size,
                                      const std::string& problem) {
    SCOPED_TRACE(descriptor);
    const Vocabulary vocabulary = test::hand_made_vocabulary(descriptor, code_size);
    vocabulary.save(dir.file("v.bbw"));
    loop::LoopDetector(vocabulary).save(dir.file("state.bbld"));
    EXPECT_EQ(run_cli("detect-loops --resume-state '" + dir.file("state.bbld") + "' --vocab '" +
                          dir.file("v.bbw") + "' -o '" + dir.file("l.csv") + "' '" + frames + "'",
                      &output),
              1)
        << output;
    EXPECT_NE(output.find("binbow: error: " + dir.file("state.bbld") + ": " + problem),
              std::string::npos)
        << output;
    // `info` refuses what resuming refuses, in the same words, with the
    // vocabulary or without.
    for (const std::string& vocab : {" --vocab '" + dir.file("v.bbw") + "'", std::string()}) {
      EXPECT_EQ(run_cli("info '" + dir.file("state.bbld") + "'" + vocab, &output), 1) << output;
      EXPECT_NE(output.find("binbow: error: " + dir.file("state.bbld") + ": " + problem),
                std::string::npos)
          << output;
    }
  };
  expect_state_error("sift", 32, "the state names the descriptor \"sift\"");
  expect_state_error("brisk", 32,
                     "the state's descriptors have 32 bytes, but brisk descriptors have 64");
}

// AKAZE keeps several float copies of the image per scale: on a large
// image with little memory, the error says which image it was.
TEST(CliFileNaming, RunningOutOfMemoryOnAnImageNamesIt) {
#if defined(BINBOW_TEST_ASAN)
  // Its shadow memory is a reservation of terabytes, which `ulimit -v` forbids.
  GTEST_SKIP() << "an AddressSanitizer build cannot run under an address-space limit; the "
                  "release build runs this test";
#endif
  TempDir dir;
  const std::string image = dir.file("large.png");
  cv::Mat pixels(4000, 4000, CV_8UC1);
  cv::randu(pixels, 0, 256);
  ASSERT_TRUE(cv::imwrite(image, pixels));
  std::string output;
  EXPECT_EQ(test::run_command("ulimit -v 1000000; '" + test::cli_path() +
                                  "' features --descriptor akaze '" + image + "'",
                              &output),
            1)
      << output;
  EXPECT_NE(output.find("binbow: error: " + image + ": "), std::string::npos) << output;
  EXPECT_NE(output.find("memory"), std::string::npos) << output;
}

}  // namespace
}  // namespace binbow
