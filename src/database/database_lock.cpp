#include "database/database_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include "binbow/database.h"
#include "binbow/error.h"
#include "core/file_io.h"
#include "core/output_path.h"

namespace binbow {
namespace detail {
namespace {

// The locks this process holds, by resolved database path. flock() locks
// belong to an open file description, so a second open() in the same
// process would conflict with the first: the process takes each lock once
// and counts the thread's nested holds.
struct Held {
  int fd = -1;
  std::thread::id owner;
  int depth = 0;
};

struct Registry {
  std::mutex mutex;
  std::condition_variable released;
  std::map<std::string, Held> held;
};

Registry& registry() {
  static Registry instance;
  return instance;
}

std::string holder_of(int fd) {
  char text[32] = {};
  const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
  if (n <= 0) return "another process";
  std::string pid(text, static_cast<std::size_t>(n));
  while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
  return pid.find_first_not_of("0123456789") == std::string::npos && !pid.empty()
             ? "process " + pid
             : "another process";
}

}  // namespace

std::string resolve_database_path(const std::string& path) {
  const std::string target = resolve_symlinks(path);
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(target, error);
  if (error) return target;
  const std::filesystem::path canonical = std::filesystem::weakly_canonical(absolute, error);
  return (error ? absolute.lexically_normal() : canonical).string();
}

void acquire_database_lock(const std::string& key, const std::string& name, double wait_seconds) {
  using Clock = std::chrono::steady_clock;
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                         std::isfinite(wait_seconds) && wait_seconds > 0 ? wait_seconds : 0));
  Registry& r = registry();
  std::unique_lock<std::mutex> guard(r.mutex);
  const std::string lock_path = key + ".lock";
  for (;;) {
    const auto found = r.held.find(key);
    if (found != r.held.end() && found->second.owner == std::this_thread::get_id()) {
      ++found->second.depth;
      return;
    }
    std::string holder = "another thread of this process";
    if (found == r.held.end()) {
      const int fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0666);
      if (fd < 0)
        throw FileError(name, "cannot open the lock file " + lock_path +
                                  " that writers of the database hold: " + std::strerror(errno));
      if (::flock(fd, LOCK_EX | LOCK_NB) == 0 || errno == ENOLCK || errno == EOPNOTSUPP) {
        // Without locks (some network file systems) writers are not kept
        // apart; saves still refuse to overwrite a change they did not load.
        const std::string pid = std::to_string(::getpid()) + "\n";
        if (::ftruncate(fd, 0) == 0) (void)::pwrite(fd, pid.data(), pid.size(), 0);
        r.held[key] = Held{fd, std::this_thread::get_id(), 1};
        return;
      }
      holder = holder_of(fd);
      ::close(fd);
    }
    if (Clock::now() >= deadline)
      throw WriteConflict(name, "another writer is changing the database (" + holder + " holds " +
                                    lock_path +
                                    "): nothing was written; try again when it is done");
    // Another thread of this process is woken by its release; another
    // process is polled.
    r.released.wait_until(guard, std::min(deadline, Clock::now() + std::chrono::milliseconds(20)));
  }
}

void release_database_lock(const std::string& key) noexcept {
  Registry& r = registry();
  std::lock_guard<std::mutex> guard(r.mutex);
  const auto found = r.held.find(key);
  if (found == r.held.end() || --found->second.depth > 0) return;
  // The pid is left in the file: the next holder overwrites it.
  ::close(found->second.fd);
  r.held.erase(found);
  r.released.notify_all();
}

SaveTarget::SaveTarget(const std::string& given) : path(given) {
  if (is_written_in_place(given)) return;
  path = resolve_database_path(given);
  prepare_output_file(given);
  writer.emplace(path);
}

}  // namespace detail

DatabaseLock::DatabaseLock(const std::string& path, double wait_seconds)
    : key_(detail::resolve_database_path(path)) {
  detail::acquire_database_lock(key_, path, wait_seconds);
}

DatabaseLock::DatabaseLock(DatabaseLock&& other) noexcept : key_(std::move(other.key_)) {
  other.key_.clear();
}

DatabaseLock::~DatabaseLock() {
  if (!key_.empty()) detail::release_database_lock(key_);
}

std::string DatabaseLock::lock_path(const std::string& path) {
  return path + ".lock";
}

}  // namespace binbow
