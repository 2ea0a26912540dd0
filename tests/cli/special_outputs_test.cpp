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

bool is_character_device(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

TEST(CliSpecialOutputs, DevNullAsAnOutputIsWrittenThroughNotReplaced) {
  TempDir dir;
  test::hand_made_vocabulary().save(dir.file("v.bbw"));
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
  EXPECT_EQ(run_cli("detect-loops -o /dev/null '" + test::write_frame_list(dir, 3) + "'", &output),
            0)
      << output;
  EXPECT_TRUE(is_character_device("/dev/null"));
  EXPECT_FALSE(std::filesystem::exists("/dev/null.run.json"));
}

}  // namespace
}  // namespace binbow
