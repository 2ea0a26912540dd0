// A long command stopped by SIGINT or SIGTERM: it stops at its next check
// point, removes its temporaries and the folders it made that stay empty,
// leaves the previous outputs as they were, says so and exits with 128 +
// the signal's number.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "support/test_support.h"

namespace binbow {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The corridor's 84 frames `rounds` times: a run that takes long enough to
// be interrupted half way.
std::string write_long_list(const test::TempDir& dir, int rounds) {
  const std::string path = dir.file("frames.txt");
  std::ofstream list(path);
  for (int round = 0; round < rounds; ++round)
    for (int i = 1; i <= 84; ++i) list << test::samples_folder() << "/" << i << ".jpg\n";
  return path;
}

// Starts the CLI with `arguments`, its stdout and stderr going to `log`.
pid_t start_cli(const std::vector<std::string>& arguments, const std::string& log) {
  std::vector<std::string> words = {test::cli_path()};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0 || ::dup2(fd, 1) < 0 || ::dup2(fd, 2) < 0) ::_exit(126);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

// Whether a file whose name holds `part` is in `folder` (or below it).
bool has_file_named(const std::string& folder, const std::string& part) {
  std::error_code error;
  for (auto it = fs::recursive_directory_iterator(folder, error);
       !error && it != fs::recursive_directory_iterator(); it.increment(error))
    if (it->path().filename().string().find(part) != std::string::npos) return true;
  return false;
}

// The process's wait status, or -1 (the process killed) if it does not end
// within `limit`.
int wait_for(pid_t pid, std::chrono::seconds limit) {
  const auto end = Clock::now() + limit;
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (Clock::now() > end) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return status;
}

// Runs detect-loops on two threads writing `loops` and its report into
// `report`, sends `signal` once it is processing frames (its temporaries
// exist), and returns its wait status; its output goes to `log`.
int interrupted_detect_loops(const test::TempDir& dir, const std::string& loops,
                             const std::string& report, int signal, const std::string& log) {
  const pid_t pid = start_cli(
      {"detect-loops", "--threads", "2", "--report", report, "-o", loops, write_long_list(dir, 12)},
      log);
  EXPECT_GT(pid, 0);
  const std::string folder = fs::path(loops).parent_path().string();
  const auto end = Clock::now() + std::chrono::seconds(15);
  while (!has_file_named(folder, ".tmp-") && Clock::now() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_TRUE(has_file_named(folder, ".tmp-")) << "detect-loops never started its outputs";
  // A few frames in: the pipeline's threads are describing frames.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ::kill(pid, signal);
  return wait_for(pid, std::chrono::seconds(15));
}

std::string text_of(const std::string& path) {
  const std::vector<std::uint8_t> bytes = test::read_file(path);
  return {bytes.begin(), bytes.end()};
}

TEST(CliInterrupt, SigintStopsDetectLoopsLeavingThePreviousOutputs) {
  test::TempDir dir;
  const std::string loops = dir.file("loops.csv");
  std::ofstream(loops) << "a previous run's loops\n";
  const std::string log = dir.file("log.txt");
  const int status = interrupted_detect_loops(dir, loops, dir.file("report"), SIGINT, log);
  const std::string output = text_of(log);
  ASSERT_TRUE(WIFEXITED(status)) << "status " << status << "\n" << output;
  EXPECT_EQ(WEXITSTATUS(status), 130) << output;
  EXPECT_NE(output.find("binbow: interrupted\n"), std::string::npos) << output;
  EXPECT_EQ(output.find("binbow: error"), std::string::npos) << output;
  EXPECT_FALSE(has_file_named(dir.path(), ".tmp-"));
  EXPECT_FALSE(fs::exists(dir.file("report"))) << "the empty report folder it made stays";
  EXPECT_EQ(text_of(loops), "a previous run's loops\n");
  EXPECT_FALSE(fs::exists(loops + ".run.json"));
}

TEST(CliInterrupt, SigtermStopsDetectLoopsAndRemovesTheFoldersItMade) {
  test::TempDir dir;
  const std::string loops = dir.file("out/run/loops.csv");
  const std::string log = dir.file("log.txt");
  const int status = interrupted_detect_loops(dir, loops, dir.file("out/report"), SIGTERM, log);
  const std::string output = text_of(log);
  ASSERT_TRUE(WIFEXITED(status)) << "status " << status << "\n" << output;
  EXPECT_EQ(WEXITSTATUS(status), 143) << output;
  EXPECT_NE(output.find("binbow: interrupted\n"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir.file("out"))) << "the folders it made for its outputs stay";
  EXPECT_FALSE(has_file_named(dir.path(), ".tmp-"));
}

}  // namespace
}  // namespace binbow
