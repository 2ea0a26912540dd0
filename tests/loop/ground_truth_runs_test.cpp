#include "loop/evaluation/ground_truth_runs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <matio.h>
#include <opencv2/imgcodecs.hpp>

#include "binbow/loop/ground_truth.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

using binbow::detail::LaterRun;
using binbow::detail::RunCollector;
using test::TempDir;
using Cells = std::vector<std::pair<std::size_t, std::size_t>>;

// The (later, earlier) pairs of symmetric cells, the brute-force way.
std::set<std::pair<std::size_t, std::size_t>> pairs_of(const Cells& cells, std::size_t frames) {
  std::set<std::pair<std::size_t, std::size_t>> pairs;
  for (const auto& [a, b] : cells)
    if (a != b && a < frames && b < frames) pairs.emplace(std::max(a, b), std::min(a, b));
  return pairs;
}

std::set<std::pair<std::size_t, std::size_t>> pairs_of(const std::vector<LaterRun>& runs) {
  std::set<std::pair<std::size_t, std::size_t>> pairs;
  for (const LaterRun& run : runs)
    for (std::uint32_t j = run.first; j < run.end; ++j) pairs.emplace(run.later, j);
  return pairs;
}

// Sorted by (later, first), each non-empty and below its later, and apart:
// two runs of one later that touch would have been merged.
void expect_canonical(const std::vector<LaterRun>& runs) {
  for (std::size_t i = 0; i < runs.size(); ++i) {
    EXPECT_LT(runs[i].first, runs[i].end);
    EXPECT_LE(runs[i].end, runs[i].later);
    if (i > 0 && runs[i - 1].later == runs[i].later) {
      EXPECT_LT(runs[i - 1].end, runs[i].first) << i;
    } else if (i > 0) {
      EXPECT_LT(runs[i - 1].later, runs[i].later) << i;
    }
  }
}

// A random symmetric matrix made of blocks, as real ground truths are, with
// noise; its cells row by row, both sides of the diagonal.
Cells block_matrix_cells(std::size_t n, std::mt19937& rng) {
  std::vector<std::uint8_t> m(n * n, 0);
  for (int block = 0; block < 6; ++block) {
    const std::size_t r = rng() % n, c = rng() % n, h = 1 + rng() % 20, w = 1 + rng() % 20;
    for (std::size_t i = r; i < std::min(n, r + h); ++i)
      for (std::size_t j = c; j < std::min(n, c + w); ++j) m[i * n + j] = m[j * n + i] = 1;
  }
  for (int noise = 0; noise < 30; ++noise) m[(rng() % n) * n + rng() % n] = 1;
  Cells cells;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      if (m[i * n + j] != 0) cells.emplace_back(i, j);
  return cells;
}

TEST(RunCollector, EqualsTheBruteForcePairsInAnyOrder) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t n = 2 + rng() % 60;
    Cells cells = block_matrix_cells(n, rng);
    // Some cells outside the frames, on the diagonal, repeated.
    cells.emplace_back(n + 3, 1);
    cells.emplace_back(2, 2);
    if (!cells.empty()) cells.push_back(cells[rng() % cells.size()]);
    const std::size_t frames = n - rng() % 2;  // sometimes cut by one
    const auto expected = pairs_of(cells, frames);
    for (int order = 0; order < 3; ++order) {
      if (order == 1) std::reverse(cells.begin(), cells.end());
      if (order == 2) std::shuffle(cells.begin(), cells.end(), rng);
      RunCollector collector(frames);
      for (const auto& [a, b] : cells) collector.add(a, b);
      const std::vector<LaterRun> runs = collector.take();
      expect_canonical(runs);
      EXPECT_EQ(pairs_of(runs), expected) << "trial " << trial << " order " << order;
    }
    // The same cells as stretches of consecutive b within a line.
    std::sort(cells.begin(), cells.end());
    RunCollector lines(frames);
    for (std::size_t i = 0; i < cells.size();) {
      std::size_t j = i + 1;
      while (j < cells.size() && cells[j].first == cells[i].first &&
             cells[j].second <= cells[j - 1].second + 1)
        ++j;
      lines.add_line(cells[i].first, cells[i].second, cells[j - 1].second + 1);
      i = j;
    }
    const std::vector<LaterRun> line_runs = lines.take();
    expect_canonical(line_runs);
    EXPECT_EQ(pairs_of(line_runs), expected) << "trial " << trial << " by lines";
  }
}

TEST(RunCollector, AnAllOnesMatrixScannedByLinesIsOneRunPerLaterFrame) {
  const std::size_t n = 500;
  RunCollector collector(n);
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = 0; b < n; ++b) collector.add(a, b);
  const std::vector<LaterRun> runs = collector.take();
  ASSERT_EQ(runs.size(), n - 1);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    EXPECT_EQ(runs[i].later, i + 1);
    EXPECT_EQ(runs[i].first, 0u);
    EXPECT_EQ(runs[i].end, i + 1);
  }
}

// What used to cost a pair each (an all-ones N × N matrix: N² / 2 pairs,
// about 1 GB at N = 10,000) now costs a range per frame.
TEST(GroundTruth, AnAllOnesImageIsOneRangePerQuery) {
  TempDir dir;
  const int n = 3000;
  ASSERT_TRUE(cv::imwrite(dir.file("ones.png"), cv::Mat(n, n, CV_8U, cv::Scalar(255))));
  const GroundTruth truth = GroundTruth::load(dir.file("ones.png"));
  EXPECT_EQ(truth.frames(), std::size_t(n));
  EXPECT_EQ(truth.range_count(), std::size_t(n - 1));
  EXPECT_EQ(truth.pair_count(), std::size_t(n) * (n - 1) / 2);
  EXPECT_EQ(truth.queries_with_loops(), std::size_t(n - 1));
  EXPECT_TRUE(truth.is_loop(n - 1, 0));
  EXPECT_TRUE(truth.is_loop(0, n - 1));
  EXPECT_FALSE(truth.is_loop(5, 5));
  EXPECT_EQ(truth.earlier_matches(4), (std::vector<std::uint32_t>{0, 1, 2, 3}));
}

void write_mat(const std::string& path, const cv::Mat& cells, matio_classes class_type,
               matio_types data_type) {
  mat_t* file = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
  ASSERT_NE(file, nullptr);
  // MATLAB is column-major: the transpose's rows are the matrix's columns.
  const cv::Mat columns = cells.t();
  std::size_t dims[2] = {static_cast<std::size_t>(cells.rows),
                         static_cast<std::size_t>(cells.cols)};
  matvar_t* var = Mat_VarCreate("gt", class_type, data_type, 2, dims,
                                const_cast<std::uint8_t*>(columns.data), MAT_F_DONT_COPY_DATA);
  ASSERT_NE(var, nullptr);
  EXPECT_EQ(Mat_VarWrite(file, var, MAT_COMPRESSION_ZLIB), 0);
  Mat_VarFree(var);
  Mat_Close(file);
}

TEST(GroundTruth, AnAllOnesMatIsOneRangePerQuery) {
  TempDir dir;
  const int n = 4000;
  write_mat(dir.file("ones.mat"), cv::Mat(n, n, CV_8U, cv::Scalar(1)), MAT_C_UINT8, MAT_T_UINT8);
  const GroundTruth truth = GroundTruth::load(dir.file("ones.mat"));
  EXPECT_EQ(truth.frames(), std::size_t(n));
  EXPECT_EQ(truth.range_count(), std::size_t(n - 1));
  EXPECT_EQ(truth.pair_count(), std::size_t(n) * (n - 1) / 2);
}

// One triangle, the other, or both: the same ground truth from an image and
// from a .mat, equal to the brute-force pairs, whichever side marks a place.
TEST(GroundTruth, EitherTriangleOfAMatrixMarksAPlace) {
  TempDir dir;
  std::mt19937 rng(11);
  const int n = 120;
  cv::Mat m(n, n, CV_8U, cv::Scalar(0));
  Cells cells;
  for (const auto& [a, b] : block_matrix_cells(n, rng)) {
    // Keep one side only, chosen at random per cell.
    const std::size_t r = rng() % 2 ? std::max(a, b) : std::min(a, b);
    const std::size_t c = r == std::max(a, b) ? std::min(a, b) : std::max(a, b);
    m.at<std::uint8_t>(static_cast<int>(r), static_cast<int>(c)) = 1;
    cells.emplace_back(r, c);
  }
  const auto expected = pairs_of(cells, n);
  ASSERT_TRUE(cv::imwrite(dir.file("gt.png"), m * 255));
  write_mat(dir.file("gt.mat"), m, MAT_C_UINT8, MAT_T_UINT8);
  for (const std::string name : {"gt.png", "gt.mat"}) {
    const GroundTruth truth = GroundTruth::load(dir.file(name));
    std::set<std::pair<std::size_t, std::size_t>> pairs;
    for (const std::size_t q : truth.loop_queries())
      for (const std::uint32_t j : truth.earlier_matches(q)) pairs.emplace(q, j);
    EXPECT_EQ(pairs, expected) << name;
    EXPECT_EQ(truth.pair_count(), expected.size()) << name;
    for (std::size_t q = 0; q < std::size_t(n); ++q)
      for (std::size_t j = 0; j < std::size_t(n); ++j)
        ASSERT_EQ(truth.is_loop(q, j), q != j && expected.count({std::max(q, j), std::min(q, j)}))
            << name << " " << q << " " << j;
  }
}

}  // namespace
}  // namespace binbow::loop
