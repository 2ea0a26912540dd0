// `binbow evaluate` on a MATLAB ground truth, against the library's numbers.
#include <gtest/gtest.h>

#include <fstream>

#include "binbow/loop/evaluation.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

TEST(EvaluateCommand, MatGroundTruthAndErrors) {
  const std::string gt = test::shared_data("lcd-groundtruth-knzhang/Lip6IndoorGroundTruth.mat");
  const GroundTruth truth = GroundTruth::load(gt);
  std::vector<Detection> detections;
  for (std::size_t q = 0; q < truth.frames() && detections.size() < 5; ++q)
    if (truth.has_loop(q)) detections.push_back({q, truth.earlier_matches(q)[0], "", "", 1, 12});
  ASSERT_EQ(detections.size(), 5u);
  detections.push_back({300, 299, "", "", 1, 12});
  ASSERT_FALSE(truth.is_loop(300, 299));
  test::TempDir dir;
  write_detections_csv(dir.file("loops.csv"), detections);
  const PrecisionRecall expected = evaluate_detections(detections, truth);

  std::string out;
  ASSERT_EQ(test::run_cli("evaluate --gt " + gt + " --sweep " + dir.file("loops.csv"), &out), 0)
      << out;
  EXPECT_NEAR(test::printed_number(out, "precision"), 5.0 / 6.0, 1e-5) << out;
  EXPECT_NEAR(test::printed_number(out, "recall"), expected.recall, 1e-5) << out;
  // Without a run record the sweep thresholds the scores (all equal here).
  EXPECT_NEAR(test::printed_number(out, "recall at 100% precision"), 0, 1e-9) << out;
  // Without a run record, the misses are known only by the detections.
  const double missed = test::printed_number(out, "missed loops");
  EXPECT_EQ(missed, double(expected.queries_with_loops - expected.queries_found)) << out;
  EXPECT_NE(out.find(": status unknown, candidate unknown\n"), std::string::npos) << out;
  // Re-running detection over another parameter needs the record.
  EXPECT_EQ(test::run_cli(
                "evaluate --gt " + gt + " --sweep --sweep-param k " + dir.file("loops.csv"), &out),
            1);
  EXPECT_NE(out.find("binbow: error: --sweep-param k re-runs detection"), std::string::npos) << out;

  detections.push_back({truth.frames(), 0, "", "", 1, 12});
  write_detections_csv(dir.file("outside.csv"), detections);
  EXPECT_NE(test::run_cli("evaluate --gt " + gt + " " + dir.file("outside.csv"), &out), 0);
  EXPECT_NE(out.find("wrong --gt"), std::string::npos) << out;
}

TEST(EvaluateCommand, ReadsLoopsOfOtherToolsByTheirQueryAndMatchColumns) {
  const std::string gt = test::shared_data("rtabmap-samples/samples_GT_pairs.txt");
  test::TempDir dir;
  std::string out;
  ASSERT_EQ(test::run_cli("evaluate --gt " + gt + " " + dir.file("missing.csv"), &out), 1) << out;
  // Frames 41 → 0 and 42 → 1 (0-based) are loops of the corridor, 60 → 5 is not.
  std::ofstream(dir.file("other.csv")) << "match,query,similarity\n0,41,0.9\n1,42,0.8\n5,60,0.7\n";
  ASSERT_EQ(test::run_cli("evaluate --gt " + gt + " " + dir.file("other.csv"), &out), 0) << out;
  EXPECT_NEAR(test::printed_number(out, "precision"), 2.0 / 3.0, 1e-5) << out;
}

}  // namespace
}  // namespace binbow::loop
