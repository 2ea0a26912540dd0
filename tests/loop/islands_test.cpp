#include "loop/detector/islands.h"

#include <gtest/gtest.h>

#include <random>

namespace binbow::loop::detail {
namespace {

std::vector<Island> islands_of(std::vector<Candidate> candidates, int gap, int min_length) {
  std::vector<Island> islands;
  compute_islands(candidates, gap, min_length, islands);
  return islands;
}

TEST(Islands, GroupsEntriesCloserThanTheGap) {
  // gap 3: ids differing by 1 or 2 join, by 3 or more split (DLoopDetector's rule).
  const auto islands = islands_of({{12, 0.5}, {10, 0.4}, {14, 0.9}, {17, 0.3}, {30, 0.8}}, 3, 1);
  ASSERT_EQ(islands.size(), 3u);
  EXPECT_EQ(islands[0].first, 10u);
  EXPECT_EQ(islands[0].last, 14u);
  EXPECT_DOUBLE_EQ(islands[0].score, 0.4 + 0.5 + 0.9);
  EXPECT_EQ(islands[0].best_entry, 14u);
  EXPECT_DOUBLE_EQ(islands[0].best_score, 0.9);
  EXPECT_EQ(islands[1].first, 17u);
  EXPECT_EQ(islands[1].last, 17u);
  EXPECT_EQ(islands[2].first, 30u);
}

TEST(Islands, DropsShortIslandsAndHandlesEmptyInput) {
  EXPECT_TRUE(islands_of({}, 3, 1).empty());
  const auto islands = islands_of({{5, 1}, {6, 1}, {20, 2}}, 3, 2);
  ASSERT_EQ(islands.size(), 1u);
  EXPECT_EQ(islands[0].first, 5u);
  EXPECT_EQ(islands[0].length(), 2);
  // Length counts entries spanned, not candidates: {5, 7} spans 3.
  EXPECT_EQ(islands_of({{5, 1}, {7, 1}}, 3, 3).size(), 1u);
}

TEST(Islands, BestIslandHasHighestSumEarliestOnTies) {
  const auto islands = islands_of({{1, 0.5}, {2, 0.5}, {10, 0.9}, {20, 1.0}}, 2, 1);
  ASSERT_EQ(islands.size(), 3u);
  const Island* best = best_island(islands);
  ASSERT_NE(best, nullptr);
  EXPECT_EQ(best->first, 1u);  // 1.0 ties with island {20}; the earliest wins
  EXPECT_EQ(best_island({}), nullptr);
}

TEST(Islands, MatchesBruteForceOnRandomInput) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Candidate> candidates;
    std::vector<bool> used(200, false);
    const int n = 1 + static_cast<int>(rng() % 40);
    for (int i = 0; i < n; ++i) {
      const EntryId e = rng() % 200;
      if (used[e]) continue;
      used[e] = true;
      candidates.push_back({e, (rng() % 1000) / 1000.0});
    }
    const int gap = 1 + static_cast<int>(rng() % 5), min_length = 1 + static_cast<int>(rng() % 4);
    const auto islands = islands_of(candidates, gap, min_length);
    // Reference: walk the id axis; every candidate lies in exactly one run.
    std::vector<Island> expected;
    int last = -1000;
    for (EntryId e = 0; e < 200; ++e) {
      if (!used[e]) continue;
      double s = 0;
      for (const auto& c : candidates)
        if (c.entry == e) s = c.score;
      if (static_cast<int>(e) - last < gap && !expected.empty()) {
        expected.back().last = e;
        expected.back().score += s;
        if (s > expected.back().best_score) {
          expected.back().best_score = s;
          expected.back().best_entry = e;
        }
      } else {
        expected.push_back({e, e, s, e, s});
      }
      last = static_cast<int>(e);
    }
    std::vector<Island> kept;
    for (const auto& i : expected)
      if (i.length() >= min_length) kept.push_back(i);
    ASSERT_EQ(islands.size(), kept.size());
    for (std::size_t i = 0; i < kept.size(); ++i) {
      EXPECT_EQ(islands[i].first, kept[i].first);
      EXPECT_EQ(islands[i].last, kept[i].last);
      EXPECT_NEAR(islands[i].score, kept[i].score, 1e-12);
      EXPECT_EQ(islands[i].best_entry, kept[i].best_entry);
    }
  }
}

Island island(EntryId first, EntryId last) {
  return {first, last, 1, first, 1};
}

TEST(TemporalWindow, CountsConsecutiveAgreeingQueries) {
  TemporalWindow window(/*max_distance_between_islands=*/3, /*max_distance_between_queries=*/2);
  EXPECT_EQ(window.update(island(10, 12), 100), 1);
  EXPECT_EQ(window.update(island(11, 13), 101), 2);  // overlaps
  EXPECT_EQ(window.update(island(16, 16), 102), 3);  // 3 after the previous island
  EXPECT_EQ(window.update(island(17, 18), 104), 4);  // 2 queries later still counts
  EXPECT_EQ(window.update(island(22, 23), 105), 1);  // 4 after the previous island: restarts
}

TEST(TemporalWindow, RestartsOnDistantIslandOrQueryGap) {
  TemporalWindow window(3, 2);
  EXPECT_EQ(window.update(island(10, 12), 100), 1);
  EXPECT_EQ(window.update(island(17, 18), 101), 1);  // 5 entries away
  EXPECT_EQ(window.update(island(17, 19), 102), 2);
  EXPECT_EQ(window.update(island(17, 19), 105), 1);  // 3 queries later
  EXPECT_EQ(window.update(island(19, 20), 106), 2);
  EXPECT_EQ(window.update(island(14, 16), 107), 3);  // before the previous island, 3 away
  EXPECT_EQ(window.consistent(), 3);
  window.clear();
  EXPECT_EQ(window.update(island(14, 16), 108), 1);
}

}  // namespace
}  // namespace binbow::loop::detail
