// A long route (2,000 frames, hundreds of places, revisits from other
// viewpoints under other exposure, noise and blur) made by `binbow
// make-route` from photographs of Debian packages no bundled vocabulary was
// trained on (scripts/route_photographs.sh): with the DEFAULT parameters and
// the bundled vocabularies, no false loop; recall is reported. Through the
// CLI, as docs/routes.md runs it.
#include <gtest/gtest.h>

#include <iostream>
#include <map>
#include <regex>
#include <string>
#include <utility>

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

class RouteAccuracy : public testing::TestWithParam<const char*> {
 protected:
  // One route for both descriptors.
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    std::string out;
    status_ = test::run_command("bash " + test::source_path("scripts/route_photographs.sh") +
                                    " > " + dir_->file("photographs.txt"),
                                &out);
    if (status_ != 0) {
      message_ = "the route photographs are missing: " + out;
      return;
    }
    status_ = test::run_cli("make-route --frames 2000 --seed 1 -o " + dir_->file("route") + " " +
                                dir_->file("photographs.txt"),
                            &out);
    message_ = out;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  static test::TempDir* dir_;
  static int status_;
  static std::string message_;
};

test::TempDir* RouteAccuracy::dir_ = nullptr;
int RouteAccuracy::status_ = -1;
std::string RouteAccuracy::message_;

TEST_P(RouteAccuracy, NoFalseLoopWithDefaults) {
  ASSERT_EQ(status_, 0) << message_;
  std::cout << message_;
  const std::string descriptor = GetParam();
  const std::string loops = dir_->file(descriptor + "_loops.csv");
  const std::string truth_file = dir_->file("route/ground_truth.txt");
  std::string out;
  ASSERT_EQ(test::run_cli("detect-loops --descriptor " + descriptor + " -o " + loops + " " +
                              dir_->file("route/frames"),
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
  // Each false loop, for whoever looks into it: the frames and their inliers.
  const GroundTruth truth = GroundTruth::load(truth_file);
  for (const Detection& d : read_detections_csv(loops))
    if (!truth.is_loop(d.query, d.match))
      ADD_FAILURE() << "false loop: query " << d.query << " match " << d.match << " score "
                    << d.score << " inliers " << d.inliers;
}

INSTANTIATE_TEST_SUITE_P(BundledVocabularies, RouteAccuracy, testing::Values("orb", "brief"),
                         [](const testing::TestParamInfo<const char*>& test) {
                           return std::string(test.param);
                         });

}  // namespace
}  // namespace binbow::loop
