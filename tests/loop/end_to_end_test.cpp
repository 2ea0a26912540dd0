// The detector on real images: rtabmap-samples (84 frames, a corridor walked
// twice) with a vocabulary trained here on unrelated images, through the
// library and through the CLI, and the HTML report in headless Chromium.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

using vision::Frame;
using vision::ImageSource;
using vision::make_extractor;

using test::shared_data;

class RealSequence : public testing::Test {
 protected:
  // A vocabulary trained here rather than a bundled one: ORB k=10, L=4 from
  // the extractor's default 1000 features of each image of two unrelated sets
  // (none of rtabmap-samples). Its recall here is 0.91; such small
  // vocabularies vary with seeds and feature counts, see docs/loop-detection.md.
  static const Vocabulary& vocabulary() {
    static const Vocabulary v = [] {
      const auto extractor = make_extractor("orb");
      ImageSource source({shared_data("opencv-doc-samples"), shared_data("dbow2-demo-images")});
      std::vector<DescriptorMatrix> images;
      Frame frame;
      while (source.next(frame)) images.push_back(extractor->extract(frame.image).descriptors);
      std::vector<DescriptorView> views(images.begin(), images.end());
      BuildOptions options;
      options.branching = 10;
      options.levels = 4;
      return Vocabulary::build(views, options);
    }();
    return v;
  }

  static std::string vocabulary_file() {
    static test::TempDir dir;
    const std::string path = dir.file("orb_k10_L4.bbw");
    if (!std::filesystem::exists(path)) vocabulary().save(path);
    return path;
  }
};

TEST_F(RealSequence, PerfectPrecisionAndHighRecallWithDefaults) {
  const GroundTruth truth = GroundTruth::load(shared_data("rtabmap-samples/samples_GT.bmp"));
  LoopDetector detector(vocabulary());
  const auto extractor = make_extractor("orb");
  ImageSource source({shared_data("rtabmap-samples/samples")});
  std::vector<Detection> detections;
  Frame frame;
  while (source.next(frame)) {
    const LoopResult r = detector.process(extractor->extract(frame.image));
    if (r.detection()) {
      EXPECT_GE(r.inliers.size(), 12u);
      EXPECT_LT(r.match + 20, r.query);  // dislocal
      detections.push_back({r.query, r.match, "", "", r.normalised_score, r.inliers.size()});
    }
  }
  ASSERT_EQ(detector.size(), 84u);
  const PrecisionRecall pr = evaluate_detections(detections, truth);
  std::cout << "rtabmap-samples, ORB k=10 L=4 stand-in vocabulary: precision " << pr.precision
            << ", recall " << pr.recall << " (" << pr.true_positives << "/" << pr.queries_with_loops
            << ")\n";
  EXPECT_EQ(pr.false_positives, 0u);
  EXPECT_DOUBLE_EQ(pr.precision, 1.0);
  EXPECT_GE(pr.recall, 0.85);
}

std::string line_value(const std::string& output, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(output, m, std::regex("(^|\n)" + key + ": ([^\n]*)"))) return "";
  return m[2];
}

TEST_F(RealSequence, CommandLineDetectEvaluateAndReportRendersInChromium) {
  test::TempDir dir;
  const std::string cli = test::cli_path();
  const std::string samples = shared_data("rtabmap-samples/samples");
  const std::string gt = shared_data("rtabmap-samples/samples_GT.bmp");
  std::string out;
  ASSERT_EQ(
      test::run_command(cli + " detect-loops --vocab " + vocabulary_file() + " --timing --report " +
                            dir.file("run-report") + " -o " + dir.file("loops.csv") + " " + samples,
                        &out),
      0)
      << out;
  for (const char* stage :
       {"features", "transform", "query", "islands", "verification", "insertion"})
    EXPECT_NE(out.find(stage), std::string::npos) << stage << "\n" << out;
  std::ifstream csv(dir.file("loops.csv"));
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "query_index,match_index,query_file,match_file,score,inliers");
  EXPECT_TRUE(std::filesystem::exists(dir.file("run-report/index.html")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("run-report/similarity.png")));

  ASSERT_EQ(test::run_command(cli + " evaluate --gt " + gt + " --sweep --report " +
                                  dir.file("report") + " " + dir.file("loops.csv"),
                              &out),
            0)
      << out;
  EXPECT_EQ(std::stod(line_value(out, "precision")), 1.0) << out;
  EXPECT_GE(std::stod(line_value(out, "recall")), 0.85) << out;
  EXPECT_GE(std::stod(line_value(out, "recall at 100% precision")), 0.85) << out;
  // Every missed ground-truth loop is listed, one line each, with its frame's status.
  const std::size_t missed = std::stoul(line_value(out, "missed loops"));
  EXPECT_EQ(missed, std::stoul(line_value(out, "queries with a loop")) -
                        std::stoul(line_value(out, "queries found")))
      << out;
  const std::regex miss_line(
      "\n  query [0-9]+: [a-z-]+, (no candidate|candidate [0-9]+ \\((right|wrong)\\))");
  EXPECT_EQ(std::size_t(std::distance(std::sregex_iterator(out.begin(), out.end(), miss_line),
                                      std::sregex_iterator())),
            missed)
      << out;
  // The α the recall at 100% precision was reached at, and the table.
  const std::string reached = line_value(out, "reached at alpha");
  ASSERT_FALSE(reached.empty()) << out;
  EXPECT_NE(out.find("\n" + reached + " "), std::string::npos) << "not a swept value: " << out;
  EXPECT_NE(out.find("\nalpha     precision     recall detections\n"), std::string::npos) << out;
  EXPECT_TRUE(std::filesystem::exists(dir.file("report/similarity.png")));

  // Another parameter, with its default values or given ones.
  std::string k_out;
  ASSERT_EQ(test::run_command(
                cli + " evaluate --gt " + gt + " --sweep --sweep-param k " + dir.file("loops.csv"),
                &k_out),
            0)
      << k_out;
  EXPECT_NE(k_out.find("\nk         precision     recall detections\n"), std::string::npos)
      << k_out;
  EXPECT_FALSE(line_value(k_out, "reached at k").empty()) << k_out;
  ASSERT_EQ(test::run_command(cli + " evaluate --gt " + gt +
                                  " --sweep --sweep-param min_inliers --sweep-values 12,30 " +
                                  dir.file("loops.csv"),
                              &k_out),
            0)
      << k_out;
  EXPECT_NE(k_out.find("\n12 "), std::string::npos) << k_out;
  EXPECT_NE(k_out.find("\n30 "), std::string::npos) << k_out;
  EXPECT_EQ(k_out.find("\n20 "), std::string::npos) << k_out;
  EXPECT_EQ(test::run_command(cli + " evaluate --gt " + gt + " --sweep --sweep-param bogus " +
                                  dir.file("loops.csv"),
                              &k_out),
            1);
  EXPECT_NE(k_out.find("binbow: error: cannot sweep \"bogus\""), std::string::npos) << k_out;
  EXPECT_NE(k_out.find("choices: alpha"), std::string::npos) << k_out;

  // The same numbers from the 1-based pair list.
  std::string pairs_out;
  ASSERT_EQ(test::run_command(cli + " evaluate --gt " +
                                  shared_data("rtabmap-samples/samples_GT_pairs.txt") + " " +
                                  dir.file("loops.csv"),
                              &pairs_out),
            0)
      << pairs_out;
  EXPECT_EQ(line_value(pairs_out, "recall"), line_value(out, "recall"));

  const std::string page = dir.file("report/index.html");
  std::ifstream in(page);
  std::stringstream html;
  html << in.rdbuf();
  for (const char* part :
       {"<svg", "id='params'", "id='timing'", "id='detections'", "data:image/jpeg;base64,",
        "id='missed'", "id='sweep'", "id='similarity'", "data:image/png;base64,", "α="})
    EXPECT_NE(html.str().find(part), std::string::npos) << part;
  EXPECT_EQ(html.str().find("http://"), html.str().find("http://www.w3.org/2000/svg"))
      << "the page must not fetch anything";

  const std::string screenshot = dir.file("report.png");
  ASSERT_TRUE(test::render_in_chromium(page, screenshot, dir.path()));
  EXPECT_GT(std::filesystem::file_size(screenshot), 20000u) << "blank page? " << out;
}

// The build tree links <build>/share/binbow to the source's data/, as an
// install would place it, so the default vocabulary is found from any build
// folder; BINBOW_DATA_DIR only comes first.
TEST_F(RealSequence, DefaultVocabularyFoundFromTheBuildTree) {
  test::TempDir dir;
  std::string out;
  const int status = test::run_command("BINBOW_DATA_DIR=" + dir.path() + " " + test::cli_path() +
                                           " detect-loops -o " + dir.file("l.csv") + " " +
                                           shared_data("rtabmap-samples/samples/1.jpg"),
                                       &out);
  EXPECT_EQ(status, 0) << out;
}

// A binbow executable with no data beside it (its commands module given by
// the environment) asks for --vocab and names the file it looked for.
TEST_F(RealSequence, MissingDefaultVocabularyAsksForVocab) {
  test::TempDir dir;
  std::filesystem::create_directories(dir.file("bin"));
  std::filesystem::copy_file(test::cli_path(), dir.file("bin/binbow"));
  std::filesystem::permissions(dir.file("bin/binbow"), std::filesystem::perms::owner_all);
  std::string out;
  const int status =
      test::run_command("BINBOW_DATA_DIR=" + dir.file("empty") +
                            " BINBOW_CLI_VISION_MODULE=" + test::cli_vision_module_path() + " " +
                            dir.file("bin/binbow") + " detect-loops -o " + dir.file("l.csv") + " " +
                            shared_data("rtabmap-samples/samples/1.jpg"),
                        &out);
  EXPECT_EQ(status, 1) << out;
  EXPECT_NE(out.find("--vocab"), std::string::npos) << out;
  EXPECT_NE(out.find("orb_default.bbw"), std::string::npos) << out;
}

}  // namespace
}  // namespace binbow::loop
