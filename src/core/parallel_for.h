// A minimal fork–join loop over std::thread: enough for the vocabulary
// builder, whose results never depend on how work is split between threads.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace binbow::detail {

// Number of worker threads for a `threads` option (0: every hardware thread).
inline unsigned resolve_thread_count(unsigned threads) {
  if (threads != 0) return threads;
  return std::max(1u, std::thread::hardware_concurrency());
}

// Calls body(index, worker) for every index in [0, count), on up to `threads`
// threads; worker 0 is the calling thread. Items are handed out in index
// order as workers become free. The first exception thrown by a body is
// rethrown here once every worker has stopped.
template <class Body>
void parallel_for(unsigned threads, std::size_t count, Body&& body) {
  const std::size_t workers = std::min<std::size_t>(std::max(1u, threads), count);
  if (workers <= 1) {
    for (std::size_t i = 0; i < count; ++i) body(i, 0u);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&](unsigned worker) {
    try {
      for (std::size_t i = next++; i < count && !failed; i = next++) body(i, worker);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      failed = true;
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (std::size_t w = 1; w < workers; ++w) {
    try {
      pool.emplace_back(work, static_cast<unsigned>(w));
    } catch (const std::system_error&) {
      break;  // fewer threads than asked: the others share the remaining items
    }
  }
  work(0);
  for (std::thread& thread : pool) thread.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace binbow::detail
