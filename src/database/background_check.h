// The check of a loaded file that Database::load leaves to a thread of its
// own (Verification::kBackground), and what it finds out on the way.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/scoring.h"

namespace binbow::detail {

// For tests: while set, a check started on a thread waits before it reads
// anything (until cleared, or its database is destroyed), so that a test
// can use a database whose check has not ended.
std::atomic<bool>& hold_background_checks();

class BackgroundCheck {
 public:
  // What a check learns while it reads every posting: what load() would
  // have computed had it read them itself.
  struct Found {
    std::vector<std::uint32_t> word_counts;  // per entry of the file
    ValueRange values;
  };
  // Reads the file; throws FileError for damage. Once `stop` is set it may
  // return anything, soon (the database is being destroyed or cleared).
  using Task = std::function<Found(const std::atomic<bool>& stop)>;

  // Runs `task` on a new thread, or now, before returning, when
  // `background` is false or no thread can be started. `path` names the
  // file when the task fails otherwise than by FileError (out of memory).
  BackgroundCheck(std::string path, Task task, bool background);
  BackgroundCheck(const BackgroundCheck&) = delete;
  BackgroundCheck& operator=(const BackgroundCheck&) = delete;
  // Stops the task and waits for its thread.
  ~BackgroundCheck();

  // Throws the FileError the check found, if it ended so (one atomic load).
  void throw_if_failed() const;
  // Whether it ended and found the file intact; found() is then final.
  bool passed() const noexcept { return state_.load(std::memory_order_acquire) == kPassed; }
  const Found& found() const noexcept { return found_; }
  // Waits for the end; throws FileError if the file is damaged.
  const Found& wait() const;

 private:
  enum State { kRunning, kPassed, kFailed };
  void run() noexcept;

  Task task_;
  std::atomic<int> state_{kRunning};
  std::atomic<bool> stop_{false};
  Found found_;
  std::string path_, problem_;  // of the FileError, when failed
  mutable std::mutex mutex_;
  mutable std::condition_variable ended_;
  std::thread thread_;
};

}  // namespace binbow::detail
