// Replays the .bbdb fuzz corpus (seed and any input that once failed) through
// the normal build: each file must load or be rejected with a FileError.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "support/test_support.h"

namespace binbow {
namespace {

TEST(BbdbFuzzCorpus, EveryInputLoadsOrIsRejectedCleanly) {
  const std::filesystem::path corpus = test::source_path("fuzz/corpus/bbdb");
  ASSERT_TRUE(std::filesystem::is_directory(corpus)) << corpus << " is missing";
  std::size_t inputs = 0, accepted = 0;
  for (const auto& entry : std::filesystem::directory_iterator(corpus)) {
    if (!entry.is_regular_file()) continue;
    SCOPED_TRACE(entry.path().string());
    const std::vector<std::uint8_t> bytes = test::read_file(entry.path().string());
    ++inputs;
    try {
      const Database database = Database::deserialize(bytes.data(), bytes.size(), "corpus");
      (void)database.query(BowVector({{0, 1.0f}}), 5);
      ++accepted;
    } catch (const FileError&) {
    }
  }
  EXPECT_GT(inputs, 0u);
  EXPECT_GT(accepted, 0u) << "no valid seed in " << corpus;
}

}  // namespace
}  // namespace binbow
