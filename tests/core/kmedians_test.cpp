#include "vocabulary/kmedians.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "binbow/descriptors.h"
#include "support/test_support.h"

namespace binbow::detail {
namespace {

struct Clustering {
  std::vector<std::uint32_t> assignment, distance;
  std::vector<std::uint8_t> centres;
  std::uint32_t count = 0;
  bool converged = false;
};

Clustering run(const DescriptorView& rows, std::uint32_t k, std::uint64_t seed,
               unsigned max_iterations = 100, unsigned threads = 1) {
  KMedians kmedians(rows.code_size, k);
  Clustering result;
  result.assignment.assign(rows.rows, 0xffffffffu);
  result.distance.assign(rows.rows, 0xffffffffu);
  kmedians.cluster(rows.data, rows.rows, seed, max_iterations, threads, result.assignment.data(),
                   result.distance.data());
  result.count = kmedians.cluster_count();
  result.centres.assign(kmedians.centres(), kmedians.centres() + result.count * rows.code_size);
  result.converged = kmedians.converged();
  std::size_t total = 0;
  for (std::uint32_t c = 0; c < result.count; ++c) total += kmedians.cluster_size(c);
  EXPECT_EQ(total, rows.rows);
  return result;
}

// Checks every invariant of a converged clustering against brute force.
void expect_converged_invariants(const DescriptorView& rows, std::uint32_t k,
                                 const Clustering& result) {
  const std::size_t code_size = rows.code_size;
  ASSERT_TRUE(result.converged);
  ASSERT_GE(result.count, 1u);
  ASSERT_LE(result.count, k);
  std::vector<std::size_t> members(result.count, 0);
  std::vector<std::vector<std::uint32_t>> bit_counts(result.count,
                                                     std::vector<std::uint32_t>(code_size * 8, 0));
  for (std::size_t i = 0; i < rows.rows; ++i) {
    std::uint32_t best = 0, best_distance = 0xffffffffu;
    for (std::uint32_t c = 0; c < result.count; ++c) {
      const std::uint32_t d =
          hamming_distance(rows.row(i), result.centres.data() + c * code_size, code_size);
      if (d < best_distance) {
        best_distance = d;
        best = c;
      }
    }
    ASSERT_EQ(result.assignment[i], best) << "row " << i << " is not in its nearest cluster";
    ASSERT_EQ(result.distance[i], best_distance) << "row " << i;
    ++members[best];
    for (std::size_t bit = 0; bit < code_size * 8; ++bit) {
      bit_counts[best][bit] += (rows.row(i)[bit / 8] >> (bit % 8)) & 1u;
    }
  }
  std::set<std::string> distinct;
  for (std::uint32_t c = 0; c < result.count; ++c) {
    EXPECT_GT(members[c], 0u) << "cluster " << c << " is empty";
    const std::uint8_t* centre = result.centres.data() + c * code_size;
    distinct.insert(std::string(reinterpret_cast<const char*>(centre), code_size));
    for (std::size_t bit = 0; bit < code_size * 8; ++bit) {
      const bool set = (centre[bit / 8] >> (bit % 8)) & 1u;
      // DBoW2's FORB::meanValue: set when at least half of the members have it.
      EXPECT_EQ(set, 2 * bit_counts[c][bit] >= members[c]) << "cluster " << c << " bit " << bit;
    }
  }
  EXPECT_EQ(distinct.size(), result.count) << "two clusters share a centre";
}

TEST(KMedians, ConvergedClusteringMeetsEveryInvariant) {
  std::mt19937_64 rng(1);
  for (const std::size_t code_size : {32u, 64u, 5u}) {
    const DescriptorMatrix rows = test::clustered_descriptors(3000, code_size, 12, 0.1, rng);
    for (const std::uint32_t k : {2u, 10u, 16u}) {
      SCOPED_TRACE("code size " + std::to_string(code_size) + ", k " + std::to_string(k));
      const Clustering result = run(rows, k, 7 + k);
      EXPECT_EQ(result.count, k);
      expect_converged_invariants(rows, k, result);
    }
  }
}

TEST(KMedians, UniformRandomRowsAlsoConverge) {
  std::mt19937_64 rng(2);
  const DescriptorMatrix rows = test::random_descriptors(2000, 32, rng);
  const Clustering result = run(rows, 10, 3, 1000);
  EXPECT_EQ(result.count, 10u);
  expect_converged_invariants(rows, 10, result);
}

TEST(KMedians, ResultDoesNotDependOnThreads) {
  std::mt19937_64 rng(3);
  // Large enough to be split into chunks when threads > 1.
  const DescriptorMatrix rows = test::clustered_descriptors(34000, 32, 50, 0.15, rng);
  const Clustering one = run(rows, 10, 11, 10, 1);
  for (const unsigned threads : {2u}) {
    const Clustering many = run(rows, 10, 11, 10, threads);
    EXPECT_EQ(one.count, many.count);
    EXPECT_EQ(one.centres, many.centres) << threads << " threads";
    EXPECT_EQ(one.assignment, many.assignment) << threads << " threads";
    EXPECT_EQ(one.distance, many.distance) << threads << " threads";
  }
}

TEST(KMedians, SameSeedSameResultOtherSeedOtherSeeding) {
  std::mt19937_64 rng(4);
  const DescriptorMatrix rows = test::random_descriptors(500, 32, rng);
  const Clustering a = run(rows, 8, 5, 0);
  const Clustering b = run(rows, 8, 5, 0);
  const Clustering c = run(rows, 8, 6, 0);
  EXPECT_EQ(a.centres, b.centres);
  EXPECT_EQ(a.assignment, b.assignment);
  EXPECT_NE(a.centres, c.centres);
}

TEST(KMedians, NoIterationsKeepsSeedsAsCentresAndNearestAssignment) {
  std::mt19937_64 rng(5);
  const DescriptorMatrix rows = test::random_descriptors(300, 32, rng);
  const Clustering result = run(rows, 6, 9, 0);
  EXPECT_FALSE(result.converged);
  ASSERT_EQ(result.count, 6u);
  for (std::uint32_t c = 0; c < result.count; ++c) {
    bool is_row = false;
    for (std::size_t i = 0; i < rows.rows() && !is_row; ++i) {
      is_row = std::memcmp(rows.row(i), result.centres.data() + c * 32, 32) == 0;
    }
    EXPECT_TRUE(is_row) << "seed " << c << " is not a training row";
  }
}

TEST(KMedians, FewerRowsThanKGivesOneClusterPerDistinctRowInOrder) {
  std::mt19937_64 rng(6);
  const DescriptorMatrix distinct = test::random_descriptors(2, 32, rng);
  DescriptorMatrix rows(32);
  rows.append(distinct.row(0));
  rows.append(distinct.row(1));
  rows.append(distinct.row(0));
  const Clustering result = run(rows, 5, 1);
  ASSERT_EQ(result.count, 2u);
  EXPECT_EQ(std::memcmp(result.centres.data(), distinct.row(0), 32), 0);
  EXPECT_EQ(std::memcmp(result.centres.data() + 32, distinct.row(1), 32), 0);
  EXPECT_EQ(result.assignment, (std::vector<std::uint32_t>{0, 1, 0}));
  EXPECT_EQ(result.distance, (std::vector<std::uint32_t>{0, 0, 0}));
}

TEST(KMedians, FewDistinctRowsGiveOneClusterEach) {
  std::mt19937_64 rng(7);
  const DescriptorMatrix distinct = test::random_descriptors(4, 32, rng);
  DescriptorMatrix rows(32);
  for (int i = 0; i < 200; ++i) rows.append(distinct.row(rng() % 4));
  for (const std::uint32_t k : {4u, 10u}) {
    const Clustering result = run(rows, k, 3);
    EXPECT_EQ(result.count, 4u);
    expect_converged_invariants(rows, k, result);
    for (const std::uint32_t d : result.distance) EXPECT_EQ(d, 0u);
  }
}

TEST(KMedians, ManyDuplicatesNeverLeaveEmptyOrEqualClusters) {
  std::mt19937_64 rng(8);
  // 12 distinct values, heavily repeated, with k close to that number: the
  // majority step often makes two centres equal and re-seeding must kick in.
  const DescriptorMatrix values = test::clustered_descriptors(12, 4, 3, 0.2, rng);
  DescriptorMatrix rows(4);
  for (int i = 0; i < 400; ++i) rows.append(values.row(rng() % 12));
  for (std::uint64_t seed = 0; seed < 40; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Clustering result = run(rows, 10, seed, 1000);
    expect_converged_invariants(rows, 10, result);
  }
}

TEST(KMedians, EmptyClustersAreReseeded) {
  std::mt19937_64 rng(9);
  // More clusters asked for than the data has: majorities collide and leave
  // clusters empty, which must be re-seeded.
  const DescriptorMatrix rows = test::clustered_descriptors(3000, 32, 12, 0.1, rng);
  std::size_t reseeded = 0;
  for (std::uint64_t seed = 0; seed < 8; ++seed) {
    KMedians kmedians(32, 16);
    Clustering result;
    result.assignment.resize(rows.rows());
    result.distance.resize(rows.rows());
    kmedians.cluster(rows.data(), rows.rows(), seed, 100, 1, result.assignment.data(),
                     result.distance.data());
    reseeded += kmedians.reseeded();
    result.count = kmedians.cluster_count();
    result.centres.assign(kmedians.centres(), kmedians.centres() + result.count * 32);
    result.converged = kmedians.converged();
    EXPECT_EQ(result.count, 16u);
    expect_converged_invariants(rows, 16, result);
  }
  EXPECT_GT(reseeded, 0u) << "the data never exercised re-seeding";
}

TEST(KMedians, MajorityTieSetsTheBit) {
  // Two rows differing in bit 0 form one cluster far from three others: the
  // tie (1 of 2) sets the bit, as DBoW2 does.
  DescriptorMatrix rows(4);
  const std::uint8_t low0[4] = {0x00, 0, 0, 0};
  const std::uint8_t low1[4] = {0x01, 0, 0, 0};
  const std::uint8_t high[4] = {0xff, 0xff, 0xff, 0xff};
  rows.append(low0);
  rows.append(low1);
  for (int i = 0; i < 3; ++i) rows.append(high);
  const Clustering result = run(rows, 2, 1);
  expect_converged_invariants(rows, 2, result);
  ASSERT_EQ(result.count, 2u);
  const std::uint8_t* low_centre = result.centres.data() + result.assignment[0] * 4;
  EXPECT_EQ(result.assignment[0], result.assignment[1]);
  EXPECT_EQ(low_centre[0], 0x01);
}

TEST(SplitMix64, BelowStaysInRangeAndCoversIt) {
  SplitMix64 rng(42);
  std::vector<int> seen(7, 0);
  for (int i = 0; i < 7000; ++i) {
    const std::uint64_t v = rng.below(7);
    ASSERT_LT(v, 7u);
    ++seen[v];
  }
  for (const int count : seen) EXPECT_GT(count, 800);
  EXPECT_NE(child_seed(1, 0), child_seed(1, 1));
  EXPECT_NE(child_seed(1, 0), child_seed(2, 0));
}

}  // namespace
}  // namespace binbow::detail
