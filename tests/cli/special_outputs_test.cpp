// Outputs that are not regular files (/dev/null, a link to it) are written
// through, never replaced by a regular file.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::run_cli;
using test::samples_folder;
using test::TempDir;

std::string write_frame_list(const TempDir& dir, int count) {
  const std::string path = dir.file("frames.txt");
  std::ofstream list(path);
  for (int i = 1; i <= count; ++i) list << samples_folder() << "/" << i << ".jpg\n";
  return path;
}

Vocabulary small_vocabulary() {
  VocabularyTree tree;
  tree.code_size = 32;
  tree.branching = 3;
  tree.levels = 2;
  tree.parent = {0, 0, 0, 0, 1, 1, 1, 2, 2};
  std::mt19937_64 rng(4);
  tree.descriptors.resize(tree.parent.size() * 32);
  for (std::uint8_t& byte : tree.descriptors) byte = static_cast<std::uint8_t>(rng());
  tree.weights = {0, 0, 0, 0.75f, 1.5f, 2.25f, 3.0f, 0.1f, 0.2f};
  return Vocabulary::from_tree(tree);
}

bool is_character_device(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

TEST(CliSpecialOutputs, DevNullAsAnOutputIsWrittenThroughNotReplaced) {
  TempDir dir;
  small_vocabulary().save(dir.file("v.bbw"));
  std::filesystem::create_symlink("/dev/null", dir.file("discard.bbw"));
  std::string output;
  for (const std::string& target : {std::string("/dev/null"), dir.file("discard.bbw")}) {
    SCOPED_TRACE(target);
    EXPECT_EQ(run_cli("convert --to bbw '" + dir.file("v.bbw") + "' '" + target + "'", &output), 0)
        << output;
    EXPECT_TRUE(is_character_device("/dev/null"));
  }
  EXPECT_TRUE(std::filesystem::is_symlink(dir.file("discard.bbw")));
  // detect-loops keeps no run record beside /dev/null.
  EXPECT_EQ(run_cli("detect-loops -o /dev/null '" + write_frame_list(dir, 3) + "'", &output), 0)
      << output;
  EXPECT_TRUE(is_character_device("/dev/null"));
  EXPECT_FALSE(std::filesystem::exists("/dev/null.run.json"));
}

}  // namespace
}  // namespace binbow
