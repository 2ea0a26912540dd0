#include "database/background_check.h"

#include <chrono>
#include <exception>
#include <system_error>
#include <utility>

#include "binbow/error.h"

namespace binbow::detail {

std::atomic<bool>& hold_background_checks() {
  static std::atomic<bool> hold{false};
  return hold;
}

BackgroundCheck::BackgroundCheck(std::string path, Task task, bool background)
    : task_(std::move(task)), path_(std::move(path)) {
  if (background) {
    try {
      thread_ = std::thread([this] {
        while (hold_background_checks().load() && !stop_.load())
          std::this_thread::sleep_for(std::chrono::milliseconds(1));
        run();
      });
      return;
    } catch (const std::system_error&) {
      // No thread to spare: checked now instead.
    }
  }
  run();
}

BackgroundCheck::~BackgroundCheck() {
  stop_.store(true, std::memory_order_relaxed);
  if (thread_.joinable()) thread_.join();
}

void BackgroundCheck::run() noexcept {
  int state = kPassed;
  try {
    found_ = task_(stop_);
  } catch (const FileError& e) {
    path_ = e.path();
    problem_ = e.problem();
    state = kFailed;
  } catch (const std::exception& e) {
    problem_ = std::string("cannot be verified: ") + e.what();
    state = kFailed;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    state_.store(state, std::memory_order_release);
  }
  ended_.notify_all();
}

void BackgroundCheck::throw_if_failed() const {
  if (state_.load(std::memory_order_acquire) == kFailed) throw FileError(path_, problem_);
}

const BackgroundCheck::Found& BackgroundCheck::wait() const {
  std::unique_lock<std::mutex> lock(mutex_);
  ended_.wait(lock, [this] { return state_.load(std::memory_order_acquire) != kRunning; });
  lock.unlock();
  throw_if_failed();
  return found_;
}

}  // namespace binbow::detail
