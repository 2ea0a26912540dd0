// Hostile inputs through the CLI: each one ends with `binbow: error: <file>:
// ...` and exit status 1, or succeeds, quickly and in bounded memory; never a
// crash or a hang.
#include <sys/stat.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "binbow/loop/evaluation.h"
#include "support/test_support.h"

namespace binbow {
namespace {

std::string run(const std::string& arguments, int* status) {
  std::string output;
  *status = test::run_cli(arguments, &output);
  return output;
}

void write_text(const std::string& path, const std::string& text) {
  test::write_file(path, std::vector<std::uint8_t>(text.begin(), text.end()));
}

void expect_error(const std::string& arguments, const std::string& file,
                  const std::string& needle) {
  int status = -1;
  const std::string out = run(arguments, &status);
  EXPECT_EQ(status, 1) << arguments << "\n" << out;
  EXPECT_NE(out.find("binbow: error: " + file + ": "), std::string::npos) << out;
  EXPECT_NE(out.find(needle), std::string::npos) << out;
}

// 50,000 levels of YAML flow sequences crashed OpenCV's parser (SIGSEGV).
TEST(CliHostileInputs, DeeplyNestedFileStorageInputsAreErrors) {
  test::TempDir dir;
  write_text(dir.file("deep.yml"), "%YAML:1.0\nalpha: " + std::string(50'000, '[') + "\n");
  const std::string frames = test::source_path("data/samples/rtabmap/samples");
  expect_error(
      "detect-loops --params " + dir.file("deep.yml") + " -o " + dir.file("l.csv") + " " + frames,
      dir.file("deep.yml"), "nested");
  write_text(dir.file("pattern.json"), "{\"x1\": " + std::string(50'000, '[') + "\n");
  expect_error("features --descriptor brief --pattern " + dir.file("pattern.json") + " " +
                   test::source_path("data/samples/rtabmap/samples/1.jpg"),
               dir.file("pattern.json"), "nested");
}

TEST(CliHostileInputs, FifosAreRefusedWithoutBlocking) {
  test::TempDir dir;
  for (const char* name : {"params.json", "frames.png", "gt.txt", "voc.bbw", "db.bbdb"})
    ASSERT_EQ(mkfifo(dir.file(name).c_str(), 0600), 0);
  const std::string frames = test::source_path("data/samples/rtabmap/samples");
  expect_error("detect-loops --params " + dir.file("params.json") + " -o " + dir.file("l.csv") +
                   " " + frames,
               dir.file("params.json"), "is a FIFO");
  expect_error("detect-loops -o " + dir.file("l.csv") + " " + dir.file("frames.png"),
               dir.file("frames.png"), "is a FIFO");
  loop::write_detections_csv(dir.file("loops.csv"), {{5, 1, "", "", 1, 12}});
  expect_error("evaluate --gt " + dir.file("gt.txt") + " " + dir.file("loops.csv"),
               dir.file("gt.txt"), "is a FIFO");
  // Vocabularies and databases are memory-mapped; info reads a database's magic first.
  expect_error("info " + dir.file("voc.bbw"), dir.file("voc.bbw"), "is a FIFO");
  expect_error(
      "detect-loops --vocab " + dir.file("voc.bbw") + " -o " + dir.file("l.csv") + " " + frames,
      dir.file("voc.bbw"), "is a FIFO");
  expect_error("db query " + dir.file("db.bbdb") + " " + frames, dir.file("db.bbdb"), "is a FIFO");
  // The run record beside loops.csv.
  ASSERT_EQ(mkfifo((dir.file("loops.csv") + ".run.json").c_str(), 0600), 0);
  expect_error("evaluate --gt " + test::source_path("data/samples/rtabmap/samples_GT.bmp") + " " +
                   dir.file("loops.csv"),
               dir.file("loops.csv") + ".run.json", "is a FIFO");
}

TEST(CliHostileInputs, PixelLimitFlagRefusesLargerImages) {
  const std::string frames = test::source_path("data/samples/rtabmap/samples");
  test::TempDir dir;
  int status = -1;
  const std::string out =
      run("build-vocab --descriptor orb --branching 2 --levels 1 --max-pixels "
          "1000 -o " +
              dir.file("v.bbw") + " " + frames,
          &status);
  EXPECT_EQ(status, 1) << out;
  EXPECT_NE(out.find("declares 512x384 pixels, more than the limit of 1000"), std::string::npos)
      << out;
}

// A solid-colour PNG is a few hundred KB at any size, yet AKAZE would take
// about 120 bytes per pixel: 12 GB for 10000x10000, 3 GB for 25 MP. Both are
// refused from the header, naming the file, unless downscaled.
TEST(CliHostileInputs, AkazeRefusesImagesAboveItsMemoryBudget) {
  test::TempDir dir;
  for (const auto& [side, name] :
       {std::pair<int, std::string>{10000, "100mp.png"}, {5000, "25mp.png"}}) {
    ASSERT_TRUE(cv::imwrite(dir.file(name), cv::Mat(side, side, CV_8UC1, cv::Scalar(90))));
    const std::string size = std::to_string(side) + "x" + std::to_string(side);
    expect_error("features --descriptor akaze " + dir.file(name), dir.file(name),
                 "image of " + size +
                     " pixels is more than 17895697 pixels, the most akaze "
                     "extracts within 2 GiB");
  }
  int status = -1;
  const std::string out =
      run("features --descriptor akaze --max-width 2000 " + dir.file("25mp.png"), &status);
  EXPECT_EQ(status, 0) << out;
  EXPECT_NE(out.find("(2000x2000)"), std::string::npos) << out;
}

// Bug report: `evaluate --gt photo.jpg` (512x384) exited 0 with a warning.
TEST(CliHostileInputs, NonSquareGroundTruthImageIsAnError) {
  test::TempDir dir;
  loop::write_detections_csv(dir.file("loops.csv"), {{5, 1, "", "", 1, 12}});
  const std::string photo = test::source_path("data/samples/rtabmap/samples/1.jpg");
  expect_error("evaluate --gt " + photo + " " + dir.file("loops.csv"), photo, "512x384");
}

// 20,000 detections swept by score against a ground truth with the pair
// "49999999 0" ran past 300 s; now one sort and one pass.
TEST(CliHostileInputs, EvaluateSweepIsLinearInTheDetections) {
  test::TempDir dir;
  write_text(dir.file("gt.txt"), "# 0-based\n49999999 0\n20009 19999\n");
  std::vector<loop::Detection> detections;
  for (std::size_t q = 0; q < 20'000; ++q)
    detections.push_back({q + 10, q, "", "", static_cast<double>(q) / 20'000, 12});
  loop::write_detections_csv(dir.file("loops.csv"), detections);
  int status = -1;
  const std::string out =
      run("evaluate --gt " + dir.file("gt.txt") + " --sweep " + dir.file("loops.csv"), &status);
  ASSERT_EQ(status, 0) << out.substr(0, 2000);
  EXPECT_NEAR(test::printed_number(out, "recall"), 0.5, 1e-9) << out.substr(0, 2000);
  EXPECT_EQ(test::printed_number(out, "detections"), 20'000) << out.substr(0, 2000);
}

}  // namespace
}  // namespace binbow
