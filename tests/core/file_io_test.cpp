// Saving: temporaries of writers that died are cleaned up, live ones are not;
// symbolic links are written through; groups of files are all or nothing.
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "core/file_io.h"
#include "support/test_support.h"

namespace binbow {
namespace {

namespace fs = std::filesystem;

std::string text_of(const std::string& path) {
  const std::vector<std::uint8_t> bytes = test::read_file(path);
  return {bytes.begin(), bytes.end()};
}

void write_text(const std::string& path, const std::string& text) {
  test::write_file(path, {text.begin(), text.end()});
}

void save(const std::string& path, const std::string& text) {
  detail::write_file_atomically(path, text.data(), text.size());
}

std::set<std::string> names_in(const std::string& directory) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory))
    names.insert(entry.path().filename().string());
  return names;
}

// Every vocabulary and database is read through MappedFile: opening a FIFO
// used to wait for a writer forever (binbow info FIFO hung).
TEST(FileIo, MappingAFifoIsRefusedWithoutBlocking) {
  test::TempDir dir;
  ASSERT_EQ(::mkfifo(dir.file("fifo").c_str(), 0600), 0);
  try {
    detail::MappedFile mapped(dir.file("fifo"));
    FAIL() << "mapped a FIFO";
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), dir.file("fifo"));
    EXPECT_NE(std::string(e.what()).find("FIFO"), std::string::npos) << e.what();
  }
}

std::size_t resident_file_kib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("RssFile:", 0) == 0) return std::stoul(line.substr(8));
  return 0;
}

// Database::load drops each section's pages once read, so that a database
// file never occupies memory whole beside the database built from it.
TEST(FileIo, ReleasedPagesOfAMappedFileLeaveMemoryAndReadBackIntact) {
  test::TempDir dir;
  std::vector<std::uint8_t> bytes(std::size_t{16} << 20);
  for (std::size_t i = 0; i < bytes.size(); ++i)
    bytes[i] = static_cast<std::uint8_t>(i * 7 + i / 4096);
  test::write_file(dir.file("big"), bytes);
  const detail::MappedFile mapped(dir.file("big"));
  ASSERT_EQ(mapped.size(), bytes.size());
  std::size_t sum = 0;
  for (std::size_t i = 0; i < mapped.size(); i += 4096) sum += mapped.data()[i];
  EXPECT_GT(sum, 0u);
  const std::size_t before = resident_file_kib();
  ASSERT_GT(before, 0u) << "no RssFile line in /proc/self/status";
  // An unaligned range: only the whole pages inside it go.
  mapped.release(mapped.data() + 100, mapped.size() - 200);
  EXPECT_LT(resident_file_kib() + 8 * 1024, before);
  EXPECT_TRUE(std::equal(bytes.begin(), bytes.end(), mapped.data()));
}

// detect-loops streams loops.csv and its run record into staged temporaries
// for the whole run: a run killed then leaves both, and the next save of
// either target sweeps them.
TEST(FileIo, StagedFilesOfAKilledWriterAreSweptByTheNextSave) {
  test::TempDir dir;
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    detail::StagedFiles staged;
    std::fputs("half a run", staged.stage(dir.file("loops.csv")));
    std::fputs("{\"frames\":[", staged.stage(dir.file("loops.csv.run.json")));
    std::fflush(nullptr);
    ::_exit(0);  // as if killed: no destructor runs, no lock is kept
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_EQ(names_in(dir.path()).size(), 2u);
  detail::StagedFiles staged;
  std::fputs("loops", staged.stage(dir.file("loops.csv")));
  std::fputs("record", staged.stage(dir.file("loops.csv.run.json")));
  staged.commit();
  EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"loops.csv", "loops.csv.run.json"}));
}

TEST(FileIo, SaveRemovesTemporariesOfDeadWritersOfTheSameTarget) {
  test::TempDir dir;
  // What `kill -9` during a save leaves: an unlocked "<target>.tmp-XXXXXX", hours old.
  write_text(dir.file("v.bbw.tmp-abcdef"), "partial");
  write_text(dir.file("v.bbw.tmp-Z9y8X7"), "partial");
  fs::last_write_time(dir.file("v.bbw.tmp-abcdef"),
                      fs::file_time_type::clock::now() - std::chrono::hours(3));
  // Not temporaries of v.bbw: left alone.
  const std::set<std::string> others = {"w.bbw.tmp-abcdef", "v.bbw.tmp-abc", "v.bbw.tmp-abcdefg",
                                        "v.bbw.tmp-abc.ef", "xv.bbw.tmp-abcdef"};
  for (const std::string& name : others) write_text(dir.file(name), "other");
  save(dir.file("v.bbw"), "new");
  std::set<std::string> expected = others;
  expected.insert("v.bbw");
  EXPECT_EQ(names_in(dir.path()), expected);
  EXPECT_EQ(text_of(dir.file("v.bbw")), "new");
}

TEST(FileIo, SaveKeepsTemporariesALiveWriterHolds) {
  test::TempDir dir;
  const std::string live = dir.file("v.bbw.tmp-live00");
  write_text(live, "being written");
  const int fd = ::open(live.c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);  // as a writer holds its temporary
  save(dir.file("v.bbw"), "new");
  EXPECT_TRUE(fs::exists(live));
  ::close(fd);
  save(dir.file("v.bbw"), "newer");  // the writer died: now it goes
  EXPECT_EQ(names_in(dir.path()), std::set<std::string>{"v.bbw"});
}

TEST(FileIo, SaveWritesThroughSymbolicLinks) {
  test::TempDir dir;
  fs::create_directory(dir.file("store"));
  write_text(dir.file("store/real.bbw"), "old");
  fs::create_symlink("store/real.bbw", dir.file("link.bbw"));       // relative
  fs::create_symlink(dir.file("link.bbw"), dir.file("link2.bbw"));  // a chain
  save(dir.file("link2.bbw"), "new");
  EXPECT_TRUE(fs::is_symlink(dir.file("link.bbw")));
  EXPECT_TRUE(fs::is_symlink(dir.file("link2.bbw")));
  EXPECT_EQ(text_of(dir.file("store/real.bbw")), "new");
  EXPECT_EQ(names_in(dir.file("store")), std::set<std::string>{"real.bbw"});
  // A dangling link: the file is created where it points.
  fs::create_symlink("store/created.bbw", dir.file("dangling.bbw"));
  save(dir.file("dangling.bbw"), "created");
  EXPECT_TRUE(fs::is_symlink(dir.file("dangling.bbw")));
  EXPECT_EQ(text_of(dir.file("store/created.bbw")), "created");
  // A loop fails cleanly.
  fs::create_symlink("loop-b", dir.file("loop-a"));
  fs::create_symlink("loop-a", dir.file("loop-b"));
  EXPECT_THROW(save(dir.file("loop-a"), "x"), FileError);
}

TEST(FileIo, SavedFilesFollowTheUmask) {
  test::TempDir dir;
  const mode_t previous = ::umask(022);
  save(dir.file("v.bbw"), "x");
  ::umask(previous);
  struct stat st {};
  ASSERT_EQ(::stat(dir.file("v.bbw").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0644u);
}

TEST(FileIo, GroupsOfFilesAreWrittenAllOrNothing) {
  test::TempDir dir;
  write_text(dir.file("loops.csv"), "old loops");
  write_text(dir.file("run.json"), "old run");
  const auto text = [](const std::string& content) {
    return [content](std::FILE* file) {
      detail::write_all(file, content.data(), content.size(), "test");
    };
  };
  const auto failing = [](std::FILE*) { throw std::runtime_error("no more data"); };
  EXPECT_THROW(detail::write_files_atomically(
                   {{dir.file("loops.csv"), text("new loops")}, {dir.file("run.json"), failing}}),
               std::runtime_error);
  EXPECT_EQ(text_of(dir.file("loops.csv")), "old loops");
  EXPECT_EQ(text_of(dir.file("run.json")), "old run");
  EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"loops.csv", "run.json"}));
  // A destination that cannot be written (its folder is a file) stops the group too.
  write_text(dir.file("blocker"), "a file");
  EXPECT_THROW(detail::write_files_atomically({{dir.file("loops.csv"), text("new loops")},
                                               {dir.file("blocker/run.json"), text("new run")}}),
               FileError);
  EXPECT_EQ(text_of(dir.file("loops.csv")), "old loops");
  EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"blocker", "loops.csv", "run.json"}));

  detail::write_files_atomically(
      {{dir.file("loops.csv"), text("new loops")}, {dir.file("run.json"), text("new run")}});
  EXPECT_EQ(text_of(dir.file("loops.csv")), "new loops");
  EXPECT_EQ(text_of(dir.file("run.json")), "new run");
  EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"blocker", "loops.csv", "run.json"}));
}

TEST(FileIo, SavesMakeMissingFoldersAndNameWhatBlocksThem) {
  test::TempDir dir;
  detail::write_file_atomically(dir.file("a/b/c.bin"), "abc", 3);
  EXPECT_EQ(text_of(dir.file("a/b/c.bin")), "abc");
  write_text(dir.file("a/file"), "not a folder");
  try {
    detail::write_file_atomically(dir.file("a/file/d.bin"), "d", 1);
    FAIL() << "a file on the way was not reported";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("is a file, not a folder"), std::string::npos) << e.what();
  }
  try {
    detail::write_file_atomically(dir.file("a/b"), "d", 1);
    FAIL() << "a folder as the destination was not reported";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("is a folder, not a file"), std::string::npos) << e.what();
  }
  EXPECT_EQ(names_in(dir.file("a")), (std::set<std::string>{"b", "file"}));
}

}  // namespace
}  // namespace binbow
