// Comparing loop detector results: detectors that must behave alike (a saved
// and restored one, one that forgot a frame at another time) give the same
// results to the bit.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "binbow/loop/loop_detector.h"

namespace binbow::test {

// Everything a LoopResult says but the times; scores bit-identical, not
// merely close.
inline void expect_same_result(const loop::LoopResult& a, const loop::LoopResult& b) {
  SCOPED_TRACE("frame " + std::to_string(a.query));
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.query, b.query);
  EXPECT_EQ(a.features, b.features);
  EXPECT_EQ(a.has_candidate, b.has_candidate);
  EXPECT_EQ(a.match, b.match);
  EXPECT_EQ(a.score, b.score);
  EXPECT_EQ(a.normalisation_score, b.normalisation_score);
  EXPECT_EQ(a.normalised_score, b.normalised_score);
  EXPECT_EQ(a.island_score, b.island_score);
  EXPECT_EQ(a.island_first, b.island_first);
  EXPECT_EQ(a.island_last, b.island_last);
  EXPECT_EQ(a.consistent_queries, b.consistent_queries);
  EXPECT_EQ(a.correspondences, b.correspondences);
  EXPECT_EQ(a.exhaustive_fallback_used, b.exhaustive_fallback_used);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_EQ(a.inlier_ratio, b.inlier_ratio);
  EXPECT_EQ(a.inlier_spread, b.inlier_spread);
  EXPECT_EQ(a.distinct_inliers, b.distinct_inliers);
  EXPECT_EQ(a.inlier_thickness, b.inlier_thickness);
  EXPECT_EQ(a.fit_evidence, b.fit_evidence);
  EXPECT_EQ(a.accepted_by, b.accepted_by);
  const loop::LoopCorroboration &x = a.corroboration, &y = b.corroboration;
  EXPECT_EQ(x.needed, y.needed);
  EXPECT_EQ(x.has_previous_loop, y.has_previous_loop);
  EXPECT_EQ(x.previous_loop_query, y.previous_loop_query);
  EXPECT_EQ(x.previous_loop_match, y.previous_loop_match);
  EXPECT_EQ(x.previous_loop_at_pace, y.previous_loop_at_pace);
  EXPECT_EQ(x.neighbour_checked, y.neighbour_checked);
  EXPECT_EQ(x.corroborating_neighbour, y.corroborating_neighbour);
  EXPECT_EQ(x.neighbour_inliers, y.neighbour_inliers);
  EXPECT_EQ(x.neighbour_shared_inliers, y.neighbour_shared_inliers);
  EXPECT_EQ(x.corroborated, y.corroborated);
}

}  // namespace binbow::test
