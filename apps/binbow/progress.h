// A progress line on stderr: redrawn in place on a terminal, one line per
// 10% step otherwise (logs stay short).
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
  void update(std::size_t done);
  void finish();

 private:
  std::string label_;
  std::size_t total_;
  std::size_t done_ = 0;
  int last_decile_ = -1;
  bool tty_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace binbow::cli
