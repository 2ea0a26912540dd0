// SIGINT (Ctrl-C) and SIGTERM stop a long command at its next check point
// (between two frames, between two stages) instead of killing it where it
// stands: the exception unwinds the command, whose destructors join its
// threads and remove its temporaries (StagedFiles), and main() exits with
// 128 + the signal's number, as a shell reports a command a signal stopped.
#pragma once

#include <atomic>
#include <exception>

namespace binbow::cli {

// Thrown by a check point once a signal arrived. Not a binbow::Error: the
// commands that go on after an Error (a report without its similarity
// matrix) must stop on this one.
class Interrupted : public std::exception {
 public:
  explicit Interrupted(int signal) noexcept : signal_(signal) {}
  const char* what() const noexcept override { return "interrupted"; }
  int signal() const noexcept { return signal_; }

 private:
  int signal_;
};

// From now on, SIGINT and SIGTERM are recorded for the check points instead
// of killing the process. The first one restores the default action of
// both: a second one kills at once, for a check point that never comes. A
// signal the process ignores (a background job's SIGINT) stays ignored.
void stop_at_check_points();

// The first signal recorded, 0 while none was.
int interruption_signal() noexcept;

// A check point: throws Interrupted once a signal was recorded.
void throw_if_interrupted();

// Where stop_at_check_points() records the signal. binbow_cli_vision has its
// own copy of these functions: the executable hands it its own flag, so
// that its check points see the signals the executable's handler records
// (vision_commands.h).
const std::atomic<int>& interruption_flag() noexcept;
void watch_interruption_flag(const std::atomic<int>* flag) noexcept;

}  // namespace binbow::cli
