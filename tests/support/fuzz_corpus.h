// Replays fuzz corpora (seeds and inputs that once crashed) through the
// normal build: each file must load or be rejected with a FileError, and
// each corpus must hold at least one valid seed.
#pragma once

#include <gtest/gtest.h>

#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "../../fuzz/fuzz_targets.h"
#include "support/test_support.h"

namespace binbow::test {

template <std::size_t N>
void replay_fuzz_corpora(const fuzz::Target (&targets)[N]) {
  for (const fuzz::Target& target : targets) {
    const std::filesystem::path corpus = source_path(std::string("fuzz/corpus/") + target.name);
    ASSERT_TRUE(std::filesystem::is_directory(corpus)) << corpus << " is missing";
    std::size_t inputs = 0, accepted = 0;
    for (const auto& entry : std::filesystem::directory_iterator(corpus)) {
      if (!entry.is_regular_file()) continue;
      SCOPED_TRACE(entry.path().string());
      const std::vector<std::uint8_t> bytes = read_file(entry.path().string());
      ++inputs;
      try {
        target.run(bytes.data(), bytes.size());
        ++accepted;
      } catch (const FileError&) {
      } catch (const std::exception& e) {
        ADD_FAILURE() << target.name << ": " << e.what();
      }
    }
    EXPECT_GT(inputs, 0u) << "no inputs in " << corpus;
    EXPECT_GT(accepted, 0u) << "no valid seed in " << corpus;
  }
}

}  // namespace binbow::test
