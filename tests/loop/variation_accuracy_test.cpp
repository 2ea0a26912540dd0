// The variation suite of docs/loop-detection.md: rtabmap-samples re-encoded
// as H.264 / H.265 video, recompressed as JPEG, with sensor noise, gamma and
// exposure changes, blur, rescaled, and combinations, made by
// scripts/make_variations.sh (ffmpeg, fixed seeds and thread counts). With
// the DEFAULT parameters and the bundled vocabularies, no case may give a
// false loop, and each finds at least the true loops of the table's "now"
// columns (the counts below). The
// "tuning" cases chose the defaults; the "validation" cases were only
// measured afterwards (docs/loop-detection.md says which of their results
// shaped a rule). Through the CLI, as
// `scripts/measure_accuracy.sh -s` measures them.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <regex>
#include <string>

#include "support/test_support.h"

namespace binbow::vision {
namespace {

struct VariationCase {
  const char* name;
  const char* part;           // "tuning" or "validation"
  int min_queries_found_orb;  // queries with a loop whose loop is found
  int min_queries_found_brief;
};

void PrintTo(const VariationCase& c, std::ostream* os) {
  *os << c.name;
}

std::string line_value(const std::string& output, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(output, m, std::regex("(^|\n)" + key + ": ([^\n]*)"))) return "";
  return m[2];
}

// Made once per build folder: the script skips the cases already made.
std::string variations_folder() {
  return (std::filesystem::path(test::cli_path()).parent_path().parent_path() / "variations")
      .string();
}

const VariationCase kCases[] = {
    VariationCase{"h264_crf18", "tuning", 38, 35},
    VariationCase{"h264_crf28", "validation", 37, 38},
    VariationCase{"h264_crf35", "tuning", 39, 32},
    VariationCase{"h265_crf18", "validation", 39, 36},
    VariationCase{"h265_crf28", "tuning", 38, 33},
    VariationCase{"h265_crf35", "validation", 37, 35},
    VariationCase{"jpeg_q8", "validation", 39, 35},
    VariationCase{"jpeg_q16", "tuning", 39, 35},
    VariationCase{"jpeg_q24", "validation", 37, 31},
    VariationCase{"noise_8", "validation", 37, 31},
    VariationCase{"noise_16", "tuning", 40, 15},
    VariationCase{"gamma_0.6", "tuning", 36, 35},
    VariationCase{"gamma_1.6", "validation", 38, 36},
    VariationCase{"exposure_x1.5", "tuning", 40, 35},
    VariationCase{"exposure_x0.5", "validation", 36, 26},
    VariationCase{"blur_1.0", "validation", 39, 31},
    VariationCase{"blur_2.0", "tuning", 37, 29},
    VariationCase{"downscale_0.5", "tuning", 33, 27},
    VariationCase{"downscale_0.75", "validation", 37, 38},
    VariationCase{"upscale_1.5", "tuning", 38, 34},
    VariationCase{"upscale_2", "validation", 36, 29},
    VariationCase{"noise_8+h264_crf28", "tuning", 38, 34},
    VariationCase{"downscale_0.75+jpeg_q16", "validation", 37, 29},
    VariationCase{"exposure_x1.5+blur_1.0+h265_crf28", "validation", 38, 38},
    VariationCase{"gamma_1.6+upscale_1.5+h264_crf35", "tuning", 35, 30},
};

TEST(VariationSuite, CasesAreTheScriptsCases) {
  std::string listed;
  ASSERT_EQ(
      test::run_command("bash " + test::source_path("scripts/make_variations.sh") + " -l", &listed),
      0)
      << listed;
  std::string expected;
  for (const VariationCase& c : kCases) expected += std::string(c.name) + " " + c.part + "\n";
  EXPECT_EQ(listed, expected);
}

class Variation : public testing::TestWithParam<VariationCase> {};

TEST_P(Variation, NoFalseLoopAndNoTrueLoopLostWithDefaults) {
  const VariationCase& c = GetParam();
  std::string out;
  ASSERT_EQ(test::run_command("command -v ffmpeg", &out), 0)
      << "ffmpeg is missing: the variation suite needs the Debian package ffmpeg "
         "(scripts/install-deps.sh)";
  const std::string folder = variations_folder();
  ASSERT_EQ(test::run_command("bash " + test::source_path("scripts/make_variations.sh") + " " +
                                  test::shared_data("rtabmap-samples/samples") + " " + folder +
                                  " '" + c.name + "'",
                              &out),
            0)
      << out;
  std::string images = folder + "/" + c.name;
  if (std::filesystem::exists(images + "/video.mp4")) images += "/video.mp4";
  test::TempDir dir;
  for (const char* descriptor : {"orb", "brief"}) {
    SCOPED_TRACE(descriptor);
    const std::string loops = dir.file(std::string(descriptor) + ".csv");
    ASSERT_EQ(test::run_command(
                  test::cli_path() + " detect-loops --descriptor " + descriptor + " --vocab " +
                      test::source_path(std::string("data/vocab/") + descriptor + "_default.bbw") +
                      " --frequency 1 -o " + loops + " '" + images + "'",
                  &out),
              0)
        << out;
    ASSERT_EQ(
        test::run_command(test::cli_path() + " evaluate --gt " +
                              test::shared_data("rtabmap-samples/samples_GT.bmp") + " " + loops,
                          &out),
        0)
        << out;
    std::cout << c.name << " (" << c.part << ") " << descriptor << ": precision "
              << line_value(out, "precision") << ", recall " << line_value(out, "recall") << "\n";
    ASSERT_EQ(line_value(out, "queries with a loop"), "44") << out;
    EXPECT_EQ(line_value(out, "false positives"), "0") << out;
    const int minimum =
        std::string(descriptor) == "orb" ? c.min_queries_found_orb : c.min_queries_found_brief;
    EXPECT_GE(std::stoi(line_value(out, "queries found")), minimum) << out;
  }
}

INSTANTIATE_TEST_SUITE_P(RtabmapSamples, Variation, testing::ValuesIn(kCases),
                         [](const testing::TestParamInfo<VariationCase>& test) {
                           std::string name = test.param.name;
                           for (char& ch : name)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return name;
                         });

}  // namespace
}  // namespace binbow::vision
