// What the database tests compare: query results to the last bit, and the
// sections of a saved .bbdb file.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "binbow/database.h"

namespace binbow::test {

// Scores must agree to the last bit, the sign of zero included.
inline std::uint64_t bits_of(double score) {
  std::uint64_t bits;
  std::memcpy(&bits, &score, sizeof bits);
  return bits;
}

// The same entries in the same order, with the same scores to the last bit
// and the same shared words.
inline void expect_same_results(const std::vector<QueryResult>& actual,
                                const std::vector<QueryResult>& expected,
                                const std::string& context) {
  ASSERT_EQ(actual.size(), expected.size()) << context;
  for (std::size_t i = 0; i < actual.size(); ++i) {
    EXPECT_EQ(actual[i].entry, expected[i].entry) << context << " rank " << i;
    EXPECT_EQ(bits_of(actual[i].score), bits_of(expected[i].score))
        << context << " rank " << i << ": " << actual[i].score << " vs " << expected[i].score;
    EXPECT_EQ(actual[i].shared_words, expected[i].shared_words) << context << " rank " << i;
  }
}

// The bytes [offset, offset + length) of a section of a .bbdb file's image,
// from its section table (docs/formats.md): 24 bytes per section after the
// 64-byte header, the offset and the length at +8 and +16.
inline std::pair<std::size_t, std::size_t> bbdb_section(const std::vector<std::uint8_t>& file,
                                                        std::uint32_t section) {
  std::uint64_t offset = 0, length = 0;
  std::memcpy(&offset, file.data() + 64 + 24 * section + 8, 8);
  std::memcpy(&length, file.data() + 64 + 24 * section + 16, 8);
  return {static_cast<std::size_t>(offset), static_cast<std::size_t>(length)};
}

}  // namespace binbow::test
