// What VINS's copy of DBoW2 returns where VINS queries (pose_graph.cpp:
// query the keyframe's descriptors with max_results 4 and max_id
// frame_index - 50, then add them), from DBoW2's own numbers: the golden
// pairwise scores of the golden images (dbow2_golden.txt, TF_IDF L1_NORM).
// Image i is queried against images 0..i-1 with max_id = i - kGap, so that
// max_id runs through DBoW2's cases (below -1; -1, which means every entry;
// 0; positive). C++11, DBoW2 API only: shared by tests/compat_vins and the
// VINS consumer of tests/package.
#ifndef BINBOW_TESTS_COMPAT_VINS_VINS_EXPECTED_H
#define BINBOW_TESTS_COMPAT_VINS_VINS_EXPECTED_H

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "dbow2_golden.h"

namespace vins_expected {

const int kGap = 3;
const int kMaxResults = 4;

// VINS's queryL1: entries sharing a word with the query (a non-zero L1
// score), with id < max_id (every id for max_id == -1) or the newest one,
// best first (lower ids first among equal scores), the first 4.
inline std::vector<std::pair<DBoW2::EntryId, double> > results(const dbow2_golden::Golden& g,
                                                               std::size_t image) {
  const std::pair<std::string, std::string> key("TF_IDF", "L1_NORM");
  if (!g.scores.count(key)) throw std::runtime_error("golden file without TF_IDF L1_NORM scores");
  const std::vector<double>& scores = g.scores.find(key)->second;
  const std::size_t n = g.images.size();
  if (scores.size() != n * n) throw std::runtime_error("golden scores are not a square matrix");
  const int max_id = static_cast<int>(image) - kGap;
  std::vector<std::pair<DBoW2::EntryId, double> > found;
  for (std::size_t id = 0; id < image; ++id) {
    const double score = scores[image * n + id];
    const bool allowed = max_id == -1 || static_cast<int>(id) < max_id || id + 1 == image;
    if (allowed && score != 0)
      found.push_back(std::make_pair(static_cast<DBoW2::EntryId>(id), score));
  }
  std::stable_sort(found.begin(), found.end(),
                   [](const std::pair<DBoW2::EntryId, double>& a,
                      const std::pair<DBoW2::EntryId, double>& b) { return a.second > b.second; });
  if (found.size() > static_cast<std::size_t>(kMaxResults)) found.resize(kMaxResults);
  return found;
}

}  // namespace vins_expected

#endif
