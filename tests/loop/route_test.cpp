// make-route: the ground truth is exact (checked against the views'
// geometry, independently of how the generator derives it), the output is a
// function of the seed, and the CLI writes what evaluate reads.
#include "binbow/loop/route.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/ground_truth.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

namespace fs = std::filesystem;

// Grey random texture: every cell is a place.
cv::Mat noise_photograph(int width, int height, std::uint64_t seed) {
  cv::Mat photo(height, width, CV_8U);
  cv::RNG rng(seed);
  rng.fill(photo, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(photo, photo, cv::Size(), 1.5);
  return photo;
}

std::vector<cv::Point2f> polygon(const std::array<cv::Point2d, 4>& corners) {
  std::vector<cv::Point2f> points;
  for (const cv::Point2d& p : corners)
    points.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
  return points;
}

RouteOptions small_options() {
  RouteOptions options;
  options.width = 160;
  options.height = 120;
  options.min_revisit_gap = 40;
  return options;
}

TEST(Route, GroundTruthListsExactlyTheOverlappingViewsOfDifferentVisits) {
  const std::vector<cv::Mat> photos = {noise_photograph(1300, 900, 1),
                                       noise_photograph(800, 1000, 2),
                                       noise_photograph(700, 500, 3)};
  RouteOptions options = small_options();
  options.frames = 1500;
  const std::vector<RoutePlace> places = route_places(photos, options);
  ASSERT_GE(places.size(), 40u);
  const Route route = plan_route({"a", "b", "c"}, places, options);
  ASSERT_EQ(route.frames.size(), options.frames);

  std::vector<std::vector<cv::Point2f>> views;
  std::vector<double> areas;
  for (std::size_t i = 0; i < route.frames.size(); ++i) {
    views.push_back(polygon(route.view_corners(i)));
    areas.push_back(cv::contourArea(views.back()));
    // Inside the place's cell, 2 pixels from its edges (bilinear sampling
    // reads no pixel of another cell).
    const cv::Rect2d& cell = route.places[route.frames[i].place].cell;
    for (const cv::Point2f& p : views.back()) {
      EXPECT_GE(p.x, cell.x + 2 - 1e-3) << "frame " << i;
      EXPECT_GE(p.y, cell.y + 2 - 1e-3) << "frame " << i;
      EXPECT_LE(p.x, cell.x + cell.width - 2 + 1e-3) << "frame " << i;
      EXPECT_LE(p.y, cell.y + cell.height - 2 + 1e-3) << "frame " << i;
    }
  }
  const auto listed = route.loop_pairs();
  const std::set<std::pair<std::size_t, std::size_t>> truth(listed.begin(), listed.end());
  ASSERT_EQ(truth.size(), listed.size());
  ASSERT_TRUE(std::is_sorted(listed.begin(), listed.end()));

  std::size_t overlapping = 0;
  double smallest_overlap = 1;
  for (std::size_t i = 0; i < route.frames.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) {
      const RouteFrame &a = route.frames[i], &b = route.frames[j];
      if (a.visit == b.visit) continue;
      const bool in_truth = truth.count({i, j}) > 0;
      if (route.places[a.place].photograph != route.places[b.place].photograph) {
        EXPECT_FALSE(in_truth) << i << " " << j << " are in different photographs";
        continue;
      }
      std::vector<cv::Point2f> common;
      const float area = cv::intersectConvexConvex(views[i], views[j], common, true);
      EXPECT_EQ(in_truth, area > 0) << i << " " << j << ": overlap " << area;
      if (area > 0) {
        ++overlapping;
        smallest_overlap = std::min(smallest_overlap, area / std::min(areas[i], areas[j]));
      }
    }
  EXPECT_EQ(overlapping, truth.size());
  EXPECT_EQ(route.loop_pair_count(), truth.size());
  // Views of one place share a large part, never a sliver.
  EXPECT_GE(smallest_overlap, 0.25);
  std::cout << "pairs " << truth.size() << ", smallest overlap " << smallest_overlap << "\n";
}

TEST(Route, VisitsAreShortAndRevisitsComeLater) {
  const std::vector<cv::Mat> photos = {noise_photograph(1300, 900, 1)};
  RouteOptions options = small_options();
  options.frames = 3000;  // more frames than the places have visits: all revisits at the end
  const Route route = plan_route({"a"}, route_places(photos, options), options);
  std::vector<std::size_t> last_end(route.places.size(), 0);
  std::vector<bool> seen(route.places.size(), false);
  std::size_t start = 0, revisits = 0;
  for (std::size_t i = 1; i <= route.frames.size(); ++i) {
    if (i < route.frames.size() && route.frames[i].visit == route.frames[start].visit) {
      EXPECT_EQ(route.frames[i].place, route.frames[start].place);
      continue;
    }
    const RouteFrame& first = route.frames[start];
    const std::size_t length = i - start;
    EXPECT_LE(length, static_cast<std::size_t>(options.max_visit_frames));
    // The detector's default dislocal (20 frames) keeps a visit's frames apart.
    EXPECT_LT(length, 20u);
    if (i < route.frames.size()) {
      EXPECT_GE(length, static_cast<std::size_t>(options.min_visit_frames));
    }
    EXPECT_EQ(first.revisit, seen[first.place]) << "visit " << first.visit;
    if (first.revisit) {
      ++revisits;
      EXPECT_GE(start - last_end[first.place], options.min_revisit_gap) << "visit " << first.visit;
    }
    seen[first.place] = true;
    last_end[first.place] = i;
    start = i;
  }
  EXPECT_GT(revisits, route.places.size());
}

// The library's whole output for one seed, file by file.
std::vector<std::pair<std::string, std::vector<std::uint8_t>>> route_files(
    const std::string& directory) {
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> files;
  for (const auto& entry : fs::recursive_directory_iterator(directory))
    if (entry.is_regular_file())
      files.emplace_back(fs::relative(entry.path(), directory).string(),
                         test::read_file(entry.path().string()));
  std::sort(files.begin(), files.end());
  return files;
}

TEST(Route, SameSeedGivesByteIdenticalOutput) {
  test::TempDir dir;
  ASSERT_TRUE(cv::imwrite(dir.file("a.png"), noise_photograph(700, 500, 1)));
  ASSERT_TRUE(cv::imwrite(dir.file("b.png"), noise_photograph(500, 700, 2)));
  RouteOptions options = small_options();
  options.frames = 120;
  const std::vector<std::string> photos = {dir.file("a.png"), dir.file("b.png")};
  make_route(photos, options, dir.file("one"));
  make_route(photos, options, dir.file("two"));
  options.seed = 2;
  make_route(photos, options, dir.file("three"));
  const auto one = route_files(dir.file("one")), two = route_files(dir.file("two")),
             three = route_files(dir.file("three"));
  ASSERT_EQ(one.size(), 120u + 3u);
  EXPECT_TRUE(one == two);
  EXPECT_FALSE(one == three);
  // The frames are what render_route_frame gives.
  EXPECT_EQ(cv::imread(dir.file("one/frames/000000.jpg"), cv::IMREAD_GRAYSCALE).size(),
            cv::Size(options.width, options.height));
}

TEST(Route, GroundTruthFileIsReadByEvaluate) {
  test::TempDir dir;
  ASSERT_TRUE(cv::imwrite(dir.file("a.png"), noise_photograph(900, 700, 4)));
  std::string out;
  ASSERT_EQ(test::run_cli("make-route --frames 300 --width 160 --height 120 --min-revisit-gap 30 "
                          "-o " +
                              dir.file("route") + " " + dir.file("a.png"),
                          &out),
            0)
      << out;
  RouteOptions options = small_options();
  options.frames = 300;
  options.min_revisit_gap = 30;
  const Route route = plan_route(
      {dir.file("a.png")},
      route_places({cv::imread(dir.file("a.png"), cv::IMREAD_GRAYSCALE)}, options), options);
  const GroundTruth truth = GroundTruth::load(dir.file("route/ground_truth.txt"));
  EXPECT_EQ(truth.pair_count(), route.loop_pairs().size());
  for (const auto& [query, match] : route.loop_pairs()) EXPECT_TRUE(truth.is_loop(query, match));
  EXPECT_EQ(
      std::distance(fs::directory_iterator(dir.file("route/frames")), fs::directory_iterator()),
      300);
  // A detections file with one true loop: evaluate counts it.
  const auto [query, match] = route.loop_pairs().front();
  const std::string text = "query_index,match_index,query_file,match_file,score,inliers\n" +
                           std::to_string(query) + "," + std::to_string(match) + ",q,m,1,50\n";
  test::write_file(dir.file("loops.csv"), std::vector<std::uint8_t>(text.begin(), text.end()));
  ASSERT_EQ(test::run_cli(
                "evaluate --gt " + dir.file("route/ground_truth.txt") + " " + dir.file("loops.csv"),
                &out),
            0)
      << out;
  EXPECT_NE(out.find("true positives: 1\n"), std::string::npos) << out;
  EXPECT_NE(out.find("queries with a loop: " + std::to_string(truth.queries_with_loops())),
            std::string::npos)
      << out;
}

TEST(Route, RefusesANonEmptyDirectoryAndPhotographsWithoutPlaces) {
  test::TempDir dir;
  ASSERT_TRUE(cv::imwrite(dir.file("a.png"), noise_photograph(900, 700, 4)));
  ASSERT_TRUE(cv::imwrite(dir.file("flat.png"), cv::Mat(700, 900, CV_8U, cv::Scalar(128))));
  std::string out;
  fs::create_directories(dir.file("full"));
  test::write_file(dir.file("full/x"), {1});
  EXPECT_EQ(test::run_cli("make-route -o " + dir.file("full") + " " + dir.file("a.png"), &out), 1);
  EXPECT_NE(out.find("binbow: error: " + dir.file("full")), std::string::npos) << out;
  EXPECT_NE(out.find("not empty"), std::string::npos) << out;
  EXPECT_EQ(test::run_cli("make-route -o " + dir.file("r") + " " + dir.file("flat.png"), &out), 1);
  EXPECT_NE(out.find("no place"), std::string::npos) << out;
  // One place revisited over a long route: quadratically many pairs.
  EXPECT_EQ(test::run_cli("make-route --frames 10000 -o " + dir.file("r") + " " + dir.file("a.png"),
                          &out),
            1);
  EXPECT_NE(out.find("more than 20000000"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir.file("r/frames")));
  EXPECT_EQ(
      test::run_cli("make-route --width 8 -o " + dir.file("r") + " " + dir.file("a.png"), &out), 1);
  EXPECT_NE(out.find("width"), std::string::npos) << out;
  EXPECT_EQ(test::run_cli("make-route -o " + dir.file("r") + " " + dir.file("missing.png"), &out),
            1);
  EXPECT_NE(out.find("missing.png"), std::string::npos) << out;
}

TEST(Route, OptionsOutOfRangeAreRefused) {
  RouteOptions options;
  options.min_visit_frames = 9;
  options.max_visit_frames = 8;
  EXPECT_THROW(check_route_options(options), InvalidArgument);
  options = RouteOptions{};
  options.cell_margin = 1;
  EXPECT_THROW(check_route_options(options), InvalidArgument);
  options = RouteOptions{};
  options.revisit_probability = 1.5;
  EXPECT_THROW(check_route_options(options), InvalidArgument);
  EXPECT_THROW(plan_route({}, {}, RouteOptions{}), InvalidArgument);
}

}  // namespace
}  // namespace binbow::loop
