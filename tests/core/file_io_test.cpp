// Saving: temporaries of writers that died are cleaned up, live ones are not;
// symbolic links are written through; groups of files are all or nothing.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
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
#include <thread>
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

// Faults in a save, injected through detail::replace_calls(): the process
// stops just before its `kill_at`-th call (as a kill -9 there would), and
// link() fails when `links_fail` (file systems without hard links).
constexpr int kKilled = 42;
int calls_made = 0;
int kill_at = 0;
bool links_fail = false;

void before_call() {
  if (++calls_made == kill_at) ::_exit(kKilled);
}
int faulty_link(const char* from, const char* to) {
  before_call();
  if (!links_fail) return ::link(from, to);
  errno = EPERM;
  return -1;
}
int faulty_rename(const char* from, const char* to) {
  before_call();
  return std::rename(from, to);
}
int faulty_unlink(const char* path) {
  before_call();
  return ::unlink(path);
}

// Saves a group of two files in a child process killed before its
// `step`-th call; returns whether the save ran to its end.
bool save_group_killed_at(const test::TempDir& dir, int step, bool without_links) {
  const pid_t child = ::fork();
  if (child == 0) {
    detail::replace_calls() = {faulty_link, faulty_rename, faulty_unlink};
    kill_at = step;
    links_fail = without_links;
    try {
      detail::write_files_atomically(
          {{dir.file("loops.csv"), [](std::FILE* f) { std::fputs("new loops", f); }},
           {dir.file("run.json"), [](std::FILE* f) { std::fputs("new run", f); }}});
    } catch (...) {
      ::_exit(1);
    }
    ::_exit(0);
  }
  int status = 0;
  EXPECT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_TRUE(WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == kKilled) << WEXITSTATUS(status);
  return WEXITSTATUS(status) == 0;
}

// A group save killed between any two of its steps, with or without hard
// links: each destination holds its old or its new content, never nothing,
// and the next save of the files leaves nothing else beside them.
void check_killed_group_saves(bool without_links) {
  bool finished = false;
  for (int step = 1; !finished && step < 40; ++step) {
    SCOPED_TRACE("killed before call " + std::to_string(step));
    test::TempDir dir;
    write_text(dir.file("loops.csv"), "old loops");
    write_text(dir.file("run.json"), "old run");
    finished = save_group_killed_at(dir, step, without_links);
    const std::string loops = text_of(dir.file("loops.csv"));
    const std::string run = text_of(dir.file("run.json"));
    EXPECT_TRUE(loops == "old loops" || loops == "new loops") << "loops.csv: '" << loops << "'";
    EXPECT_TRUE(run == "old run" || run == "new run") << "run.json: '" << run << "'";
    if (finished) {
      EXPECT_EQ(loops + run, "new loopsnew run");
    }
    save(dir.file("loops.csv"), "later loops");
    save(dir.file("run.json"), "later run");
    EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"loops.csv", "run.json"}));
  }
  EXPECT_TRUE(finished);
}

TEST(FileIo, KilledSavesLeaveTheOldOrNewFilesAndTheNextSaveSweepsTheRest) {
  check_killed_group_saves(false);
}

TEST(FileIo, WithoutHardLinksAKilledSaveStillLeavesEveryDestination) {
  check_killed_group_saves(true);
}

void set_age(const std::string& path, std::chrono::seconds age) {
  fs::last_write_time(path, fs::file_time_type::clock::now() - age);
}

// What saves of older versions left: backups no writer holds. A backup goes
// only when the destination makes it redundant.
TEST(FileIo, ASaveRemovesBackupsOfItsDestinationOnlyWhenRedundant) {
  test::TempDir dir;
  write_text(dir.file("v.bbw"), "current");
  set_age(dir.file("v.bbw"), std::chrono::hours(1));
  fs::create_hard_link(dir.file("v.bbw"), dir.file("v.bbw.old-linked"));  // the same file
  write_text(dir.file("v.bbw.old-older1"), "older");
  set_age(dir.file("v.bbw.old-older1"), std::chrono::hours(2));
  write_text(dir.file("v.bbw.old-newer1"), "newer than the destination");  // not provably stale
  write_text(dir.file("v.bbw.old-locked"), "older, held by a live save");
  set_age(dir.file("v.bbw.old-locked"), std::chrono::hours(2));
  write_text(dir.file("w.bbw.old-abcdef"), "another file's");
  set_age(dir.file("w.bbw.old-abcdef"), std::chrono::hours(2));
  const int fd = ::open(dir.file("v.bbw.old-locked").c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_SH), 0);
  save(dir.file("v.bbw"), "new");
  EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"v.bbw", "v.bbw.old-newer1",
                                                         "v.bbw.old-locked", "w.bbw.old-abcdef"}));
  ::close(fd);
  EXPECT_EQ(text_of(dir.file("v.bbw.old-newer1")), "newer than the destination");
  // The holder died, and the destination was saved after both backups.
  save(dir.file("v.bbw"), "newer");
  EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"v.bbw", "w.bbw.old-abcdef"}));
}

// A backup without its destination is the only copy of the user's data: it
// is put back, so a save that then fails leaves the previous version.
TEST(FileIo, AMissingDestinationIsRestoredFromItsNewestBackup) {
  test::TempDir dir;
  write_text(dir.file("v.bbw.old-aaaaaa"), "older");
  set_age(dir.file("v.bbw.old-aaaaaa"), std::chrono::hours(2));
  write_text(dir.file("v.bbw.old-bbbbbb"), "previous");
  set_age(dir.file("v.bbw.old-bbbbbb"), std::chrono::hours(1));
  EXPECT_THROW(detail::write_file_atomically(
                   dir.file("v.bbw"), [](std::FILE*) { throw std::runtime_error("disk full"); }),
               std::runtime_error);
  EXPECT_EQ(text_of(dir.file("v.bbw")), "previous");
  EXPECT_EQ(names_in(dir.path()), std::set<std::string>{"v.bbw"});
}

// Everything the pipe's reader gets before the writer is done, or a pause
// of 5 s without data (a save that never wrote to it).
std::string read_pipe(int fd, std::size_t expected) {
  std::string got;
  std::vector<char> buffer(1 << 16);
  while (got.size() < expected) {
    pollfd ready{fd, POLLIN, 0};
    if (::poll(&ready, 1, 5000) <= 0) break;
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n <= 0) break;
    got.append(buffer.data(), static_cast<std::size_t>(n));
  }
  return got;
}

// `binbow ... -o fifo` feeds a reader; the FIFO stays.
TEST(FileIo, AFifoIsWrittenThroughNotReplaced) {
  test::TempDir dir;
  ASSERT_EQ(::mkfifo(dir.file("fifo").c_str(), 0600), 0);
  fs::create_symlink("fifo", dir.file("link"));
  // Larger than a pipe's buffer: the save needs the reader as it writes.
  std::string text(std::size_t{1} << 20, 'x');
  for (std::size_t i = 0; i < text.size(); i += 1000) text[i] = static_cast<char>('a' + i % 26);
  // Opened read-write, the reader never waits for a writer nor blocks the test.
  const int fd = ::open(dir.file("fifo").c_str(), O_RDWR | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  std::string got;
  std::thread reader([&] { got = read_pipe(fd, 2 * text.size()); });
  save(dir.file("fifo"), text);
  save(dir.file("link"), text);  // through a symbolic link
  reader.join();
  ::close(fd);
  EXPECT_TRUE(got == text + text) << got.size() << " bytes read";
  struct stat st {};
  ASSERT_EQ(::lstat(dir.file("fifo").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_TRUE(fs::is_symlink(dir.file("link")));
  EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"fifo", "link"}));
}

TEST(FileIo, DevNullIsWrittenThroughNotReplaced) {
  test::TempDir dir;
  fs::create_symlink("/dev/null", dir.file("discard"));
  save("/dev/null", "nothing");
  save(dir.file("discard"), "nothing");
  detail::write_files_atomically(
      {{dir.file("a"), [](std::FILE* f) { std::fputs("a", f); }},
       {dir.file("discard"), [](std::FILE* f) { std::fputs("nothing", f); }}});
  struct stat st {};
  ASSERT_EQ(::lstat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  EXPECT_TRUE(fs::is_symlink(dir.file("discard")));
  EXPECT_EQ(text_of(dir.file("a")), "a");
  EXPECT_EQ(names_in(dir.path()), (std::set<std::string>{"a", "discard"}));
  for (const std::string& name : names_in("/dev")) EXPECT_NE(name.rfind("null.", 0), 0u) << name;
}

// /dev/stdout names the descriptor the shell opened: written through it, an
// appended log keeps its lines and stays the same file.
TEST(FileIo, DevStdoutIsTheProcessStandardOutput) {
  test::TempDir dir;
  write_text(dir.file("log"), "earlier\n");
  struct stat before {};
  ASSERT_EQ(::stat(dir.file("log").c_str(), &before), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const int log = ::open(dir.file("log").c_str(), O_WRONLY | O_APPEND);
    if (log < 0 || ::dup2(log, 1) != 1) ::_exit(2);
    try {
      save("/dev/stdout", "saved\n");
      save("/dev/fd/1", "again\n");
    } catch (...) {
      ::_exit(1);
    }
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(text_of(dir.file("log")), "earlier\nsaved\nagain\n");
  struct stat after {};
  ASSERT_EQ(::stat(dir.file("log").c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino);
  EXPECT_EQ(names_in(dir.path()), std::set<std::string>{"log"});
}

// A socket (or a block device) is never what a user means to save into.
TEST(FileIo, ASocketIsRefusedNotReplaced) {
  test::TempDir dir;
  const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(sock, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  const std::string path = dir.file("sock");
  ASSERT_LT(path.size(), sizeof(address.sun_path));
  std::copy(path.begin(), path.end(), address.sun_path);
  ASSERT_EQ(::bind(sock, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
  try {
    save(path, "x");
    ADD_FAILURE() << "saved into a socket";
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_NE(std::string(e.what()).find("is a socket"), std::string::npos) << e.what();
  }
  ::close(sock);
  struct stat st {};
  ASSERT_EQ(::lstat(path.c_str(), &st), 0);
  EXPECT_TRUE(S_ISSOCK(st.st_mode));
}

}  // namespace
}  // namespace binbow
