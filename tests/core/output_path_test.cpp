// Output paths made ready before a command's work: missing folders created,
// impossible paths refused with the path and what to do.
#include "core/output_path.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "binbow/error.h"
#include "support/test_support.h"

namespace binbow::detail {
namespace {

namespace fs = std::filesystem;

// The FileError message of `call`, or a test failure when it does not throw one.
template <typename Call>
std::string file_error(Call call) {
  try {
    call();
  } catch (const FileError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no FileError";
  return {};
}

TEST(OutputPath, CreatesMissingParentFolders) {
  test::TempDir dir;
  prepare_output_file(dir.file("a/b/c/loops.csv"));
  EXPECT_TRUE(fs::is_directory(dir.file("a/b/c")));
  EXPECT_FALSE(fs::exists(dir.file("a/b/c/loops.csv")));  // nothing written yet

  prepare_output_directory(dir.file("report/x"));
  EXPECT_TRUE(fs::is_directory(dir.file("report/x")));
  prepare_output_directory(dir.file("report/x"));  // existing: fine
  prepare_output_file(dir.file("report/x/index.html"));
}

TEST(OutputPath, AFileInTheWayIsNamedWithWhatToDo) {
  test::TempDir dir;
  test::write_file(dir.file("plain"), {'x'});
  const std::string message =
      file_error([&] { prepare_output_file(dir.file("plain/sub/loops.csv")); });
  EXPECT_EQ(message.rfind(dir.file("plain/sub/loops.csv") + ": ", 0), 0u) << message;
  EXPECT_NE(message.find(dir.file("plain") + " is a file, not a folder"), std::string::npos)
      << message;
  EXPECT_NE(message.find("choose another path"), std::string::npos) << message;

  const std::string directory_message =
      file_error([&] { prepare_output_directory(dir.file("plain")); });
  EXPECT_NE(directory_message.find(dir.file("plain") + ": exists and is not a folder"),
            std::string::npos)
      << directory_message;
}

TEST(OutputPath, AFolderIsNotAnOutputFile) {
  test::TempDir dir;
  EXPECT_NE(file_error([&] { prepare_output_file(dir.path()); }).find("is a folder, not a file"),
            std::string::npos);
  EXPECT_NE(
      file_error([&] { prepare_output_file(dir.file("new/")); }).find("is a folder, not a file"),
      std::string::npos);
  EXPECT_FALSE(fs::exists(dir.file("new")));
}

TEST(OutputPath, AFileInTheCurrentFolderNeedsNoParent) {
  // "loops.csv" has no parent part: its folder is the current one.
  test::TempDir dir;
  const fs::path previous = fs::current_path();
  fs::current_path(dir.path());
  EXPECT_NO_THROW(prepare_output_file("loops.csv"));
  fs::current_path(previous);
}

}  // namespace
}  // namespace binbow::detail
