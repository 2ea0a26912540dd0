// A long route (2,000 frames, hundreds of places, revisits from other
// viewpoints under other exposure, noise and blur) made by `binbow
// make-route` from photographs of Debian packages no bundled vocabulary was
// trained on (scripts/route_photographs.sh): with the DEFAULT parameters and
// the bundled vocabularies, no false loop; recall is reported. Through the
// CLI, as docs/routes.md runs it.
#include <gtest/gtest.h>

#include <iostream>
#include <regex>
#include <string>

#include "binbow/loop/ground_truth.h"
#include "binbow/loop/loops_csv.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

std::string line_value(const std::string& output, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(output, m, std::regex("(^|\n)" + key + ": ([^\n]*)"))) return "";
  return m[2];
}

// Precision and recall of one descriptor's run over the route in `dir`.
void expect_no_false_loop(const test::TempDir& dir, const std::string& descriptor) {
  SCOPED_TRACE(descriptor);
  const std::string loops = dir.file(descriptor + "_loops.csv");
  const std::string truth_file = dir.file("route/ground_truth.txt");
  std::string out;
  ASSERT_EQ(test::run_cli("detect-loops --descriptor " + descriptor + " -o " + loops + " " +
                              dir.file("route/frames"),
                          &out),
            0)
      << out;
  ASSERT_EQ(test::run_cli("evaluate --gt " + truth_file + " " + loops, &out), 0) << out;
  std::cout << descriptor << " on a 2000-frame route: precision " << line_value(out, "precision")
            << ", recall " << line_value(out, "recall") << " (" << line_value(out, "queries found")
            << " of " << line_value(out, "queries with a loop") << " queries)\n";
  ASSERT_GT(std::stoul(line_value(out, "queries with a loop")), 300u) << out;
  EXPECT_GT(std::stoul(line_value(out, "true positives")), 0u) << out;
  EXPECT_EQ(line_value(out, "false positives"), "0") << out;
  // A revisit of 5 to 12 frames cannot wait for k + 1 consistent queries:
  // recall stays near 0.33 unless strong fits skip the temporal test. Under
  // the revisits' blur and noise many of those fits explain little of the
  // views and stand on a neighbour of the match that fits the same query
  // features (min_uncorroborated_view_agreement); rejecting them would bring
  // ORB's recall down to 0.42.
  EXPECT_GE(std::stod(line_value(out, "recall")), 0.5) << out;
  // Each false loop, for whoever looks into it: the frames, score and inliers.
  const GroundTruth truth = GroundTruth::load(truth_file);
  for (const Detection& d : read_detections_csv(loops))
    if (!truth.is_loop(d.query, d.match))
      ADD_FAILURE() << "false loop: query " << d.query << " match " << d.match << " score "
                    << d.score << " inliers " << d.inliers;
}

// One route (made once: most of the test's time after detection) for both
// bundled vocabularies.
TEST(RouteAccuracy, NoFalseLoopWithTheBundledVocabularies) {
  test::TempDir dir;
  std::string out;
  ASSERT_EQ(test::run_command("bash " + test::source_path("scripts/route_photographs.sh") + " > " +
                                  dir.file("photographs.txt"),
                              &out),
            0)
      << "the route photographs are missing: " << out;
  ASSERT_EQ(test::run_cli("make-route --frames 2000 --seed 1 -o " + dir.file("route") + " " +
                              dir.file("photographs.txt"),
                          &out),
            0)
      << out;
  std::cout << out;
  expect_no_false_loop(dir, "orb");
  expect_no_false_loop(dir, "brief");
}

}  // namespace
}  // namespace binbow::loop
