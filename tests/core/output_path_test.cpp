// Output paths made ready before a command's work: missing folders created,
// impossible paths refused with the path and what to do.
#include "core/output_path.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
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

// Outputs written in place are ready as they are; a socket is refused
// before any work, naming what it is.
TEST(OutputPath, DevicesAndFifosAreReadyAndSocketsAreRefused) {
  test::TempDir dir;
  ASSERT_EQ(::mkfifo(dir.file("fifo").c_str(), 0600), 0);
  EXPECT_TRUE(is_written_in_place(dir.file("fifo")));
  EXPECT_TRUE(is_written_in_place("/dev/null"));
  EXPECT_TRUE(is_written_in_place("/dev/stdout"));
  EXPECT_FALSE(is_written_in_place(dir.file("missing")));
  EXPECT_NO_THROW(prepare_output_file(dir.file("fifo")));
  EXPECT_NO_THROW(prepare_output_file("/dev/null"));
  EXPECT_EQ(own_descriptor("/dev/stdout"), 1);
  EXPECT_EQ(own_descriptor("/dev/fd/2"), 2);
  EXPECT_EQ(own_descriptor(dir.file("fifo")), -1);

  const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(sock, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  const std::string path = dir.file("sock");
  ASSERT_LT(path.size(), sizeof(address.sun_path));
  std::copy(path.begin(), path.end(), address.sun_path);
  ASSERT_EQ(::bind(sock, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
  const std::string message = file_error([&] { prepare_output_file(path); });
  EXPECT_EQ(message.rfind(path + ": is a socket", 0), 0u) << message;
  ::close(sock);
}

}  // namespace
}  // namespace binbow::detail
