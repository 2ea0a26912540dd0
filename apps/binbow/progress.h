// A progress line on stderr: redrawn in place on a terminal. Elsewhere (a log
// file, CI) no redraws: a plain line every kLogInterval while a stage runs,
// so that short runs log only the closing "LABEL: N done in Ts" line.
// Nothing with --quiet (invocation.h).
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace binbow::cli {

class Progress {
 public:
  // total 0: unknown length (counts only).
  Progress(std::string label, std::size_t total);
  ~Progress();
  // Also a check point (interruption.h): throws Interrupted once SIGINT or
  // SIGTERM arrived, so that every stage that shows its progress stops there.
  void update(std::size_t done);
  void finish();

  static constexpr std::chrono::seconds kLogInterval{10};

 private:
  std::string label_;
  std::size_t total_;
  std::size_t done_ = 0;
  bool tty_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace binbow::cli
