// A reader-writer lock under which writers cannot starve.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <mutex>

namespace binbow::detail {

// std::shared_mutex is glibc's reader-preferring rwlock: while any reader
// holds it a new reader gets in, so threads querying back to back kept
// add() waiting for seconds. Here a writer first closes the entry to new
// readers, then waits only for the readers already inside. Readers and
// writers that arrive while a writer holds the lock queue at the same entry
// and get in in whatever order they wake, so neither side starves the other.
// Meets the SharedMutex requirements used by std::unique_lock and
// std::shared_lock (lock, unlock, lock_shared, unlock_shared); not recursive.
class WriterPriorityMutex {
 public:
  void lock() {
    std::unique_lock<std::mutex> guard(state_);
    entry_open_.wait(guard, [this] { return !writer_; });
    writer_ = true;
    readers_gone_.wait(guard, [this] { return readers_ == 0; });
  }
  void unlock() {
    {
      const std::lock_guard<std::mutex> guard(state_);
      writer_ = false;
    }
    entry_open_.notify_all();
  }
  void lock_shared() {
    std::unique_lock<std::mutex> guard(state_);
    entry_open_.wait(guard, [this] { return !writer_; });
    ++readers_;
  }
  void unlock_shared() {
    bool last_before_writer;
    {
      const std::lock_guard<std::mutex> guard(state_);
      --readers_;
      last_before_writer = writer_ && readers_ == 0;
    }
    if (last_before_writer) readers_gone_.notify_one();
  }

 private:
  std::mutex state_;
  std::condition_variable entry_open_;    // writer_ became false
  std::condition_variable readers_gone_;  // readers_ became 0 while a writer waits
  bool writer_ = false;                   // a writer holds the lock or waits for readers to leave
  std::size_t readers_ = 0;               // readers holding the lock
};

}  // namespace binbow::detail
