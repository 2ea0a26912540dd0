#include <gtest/gtest.h>

#include <random>

#include "binbow/descriptors.h"
#include "binbow/error.h"
#include "core/crc32c.h"
#include "core/kernels.h"
#include "support/test_support.h"

namespace binbow {
namespace {

TEST(Hamming, EveryKernelMatchesBitCountingForAllLengths) {
  std::mt19937_64 rng(7);
  for (std::size_t code_size : {1, 3, 7, 8, 9, 16, 31, 32, 33, 61, 64, 65, 128}) {
    const auto m = test::random_descriptors(50, code_size, rng);
    for (std::size_t i = 0; i + 1 < m.rows(); ++i) {
      const std::uint32_t expected = test::bit_distance(m.row(i), m.row(i + 1), code_size);
      EXPECT_EQ(hamming_distance(m.row(i), m.row(i + 1), code_size), expected) << code_size;
      EXPECT_EQ(detail::generic_kernels().hamming(m.row(i), m.row(i + 1), code_size), expected);
    }
  }
}

TEST(Hamming, ExtremesAndIdentity) {
  std::vector<std::uint8_t> zeros(32, 0), ones(32, 0xff);
  EXPECT_EQ(hamming_distance(zeros.data(), ones.data(), 32), 256u);
  EXPECT_EQ(hamming_distance(ones.data(), ones.data(), 32), 0u);
}

TEST(Hamming, NearestNeighborsMatchesLinearSearchWithLowestIndexOnTies) {
  std::mt19937_64 rng(11);
  for (std::size_t code_size : {32, 64, 20}) {
    auto candidates = test::random_descriptors(40, code_size, rng);
    // Duplicate a row so that ties happen.
    std::copy_n(candidates.row(3), code_size, candidates.row(17));
    auto queries = test::random_descriptors(100, code_size, rng);
    std::copy_n(candidates.row(17), code_size, queries.row(0));
    std::vector<std::uint32_t> index(queries.rows()), distance(queries.rows());
    nearest_neighbors(queries, candidates, index.data(), distance.data());
    for (std::size_t q = 0; q < queries.rows(); ++q) {
      std::uint32_t best = ~0u, best_i = 0;
      for (std::size_t c = 0; c < candidates.rows(); ++c) {
        const auto d = test::bit_distance(queries.row(q), candidates.row(c), code_size);
        if (d < best) best = d, best_i = static_cast<std::uint32_t>(c);
      }
      EXPECT_EQ(index[q], best_i);
      EXPECT_EQ(distance[q], best);
    }
    EXPECT_EQ(index[0], 3u);
  }
}

TEST(Hamming, NearestNeighborsRejectsMismatchedInput) {
  DescriptorMatrix a(2, 32), b(2, 64), empty(0, 32);
  std::uint32_t i[2], d[2];
  EXPECT_THROW(nearest_neighbors(a, b, i, d), InvalidArgument);
  EXPECT_THROW(nearest_neighbors(a, empty, i, d), InvalidArgument);
}

TEST(Crc32c, StandardCheckValue) {
  const char text[] = "123456789";
  EXPECT_EQ(detail::crc32c(text, 9), 0xE3069283u);
  // Incremental equals one-shot.
  EXPECT_EQ(detail::crc32c(text + 4, 5, detail::crc32c(text, 4)), 0xE3069283u);
}

TEST(Crc32c, DispatchedStreamsEqualPortableTableForAllSizes) {
  std::mt19937_64 rng(5);
  std::vector<std::uint8_t> bytes(100000);
  for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
  for (std::size_t size : {0, 1, 7, 8, 9, 4095, 12287, 12288, 12289, 50001, 100000}) {
    EXPECT_EQ(detail::crc32c(bytes.data(), size), detail::crc32c_portable(bytes.data(), size))
        << size;
    EXPECT_EQ(detail::crc32c(bytes.data(), size, 0x1234u),
              detail::crc32c_portable(bytes.data(), size, 0x1234u));
  }
  const std::uint32_t a = detail::crc32c(bytes.data(), 777);
  const std::uint32_t b = detail::crc32c(bytes.data() + 777, 5000);
  EXPECT_EQ(detail::crc32c_combine(a, b, 5000), detail::crc32c(bytes.data(), 5777));
}

TEST(DescriptorMatrix, AppendRowsAndViews) {
  DescriptorMatrix m(4);
  const std::uint8_t row[4] = {1, 2, 3, 4};
  m.append(row);
  m.append(m.view());
  ASSERT_EQ(m.rows(), 2u);
  EXPECT_EQ(m.row(1)[3], 4);
  EXPECT_EQ(m.view().slice(1, 1).row(0)[0], 1);
  DescriptorMatrix other(8);
  EXPECT_THROW(other.append(m.view()), InvalidArgument);
}

}  // namespace
}  // namespace binbow
