#include "progress.h"

#include <unistd.h>
#include <cstdio>

#include "interruption.h"
#include "invocation.h"

namespace binbow::cli {

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(total),
      tty_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() {
  finish();
}

void Progress::update(std::size_t done) {
  throw_if_interrupted();
  done_ = done;
  if (invocation().quiet) return;
  const auto now = std::chrono::steady_clock::now();
  const double seconds = std::chrono::duration<double>(now - start_).count();
  if (tty_) {
    if (now - last_draw_ < std::chrono::milliseconds(100) && done != total_) return;
    last_draw_ = now;
    if (total_ > 0) {
      const int width = 30;
      const int filled = static_cast<int>(width * done / total_);
      std::fprintf(stderr, "\r%s [%.*s%*s] %zu/%zu %.1fs", label_.c_str(), filled,
                   "==============================", width - filled, "", done, total_, seconds);
    } else {
      std::fprintf(stderr, "\r%s %zu %.1fs", label_.c_str(), done, seconds);
    }
    std::fflush(stderr);
    return;
  }
  // A log: a plain line now and then for long stages, none for short ones.
  if (now - last_draw_ < kLogInterval) return;
  last_draw_ = now;
  if (total_ > 0)
    std::fprintf(stderr, "%s: %zu/%zu (%zu%%) %.1fs\n", label_.c_str(), done, total_,
                 100 * done / total_, seconds);
  else
    std::fprintf(stderr, "%s: %zu %.1fs\n", label_.c_str(), done, seconds);
  std::fflush(stderr);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (invocation().quiet) return;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (tty_) std::fprintf(stderr, "\r\033[K");
  std::fprintf(stderr, "%s: %zu done in %.2fs\n", label_.c_str(), done_, seconds);
}

}  // namespace binbow::cli
