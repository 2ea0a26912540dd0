#include "interruption.h"

#include <signal.h>

namespace binbow::cli {
namespace {

static_assert(std::atomic<int>::is_always_lock_free, "the flag is set by a signal handler");

constexpr int kSignals[] = {SIGINT, SIGTERM};

std::atomic<int> received{0};
std::atomic<const std::atomic<int>*> watched{&received};
// Whether the handler replaced the signal's action (it was not ignored).
std::atomic<bool> handled[2] = {false, false};

void on_signal(int number) {
  int none = 0;
  received.compare_exchange_strong(none, number);
  // Async-signal-safe: the next SIGINT or SIGTERM kills.
  struct sigaction default_action {};
  default_action.sa_handler = SIG_DFL;
  sigemptyset(&default_action.sa_mask);
  for (int i = 0; i < 2; ++i)
    if (handled[i].load()) sigaction(kSignals[i], &default_action, nullptr);
}

}  // namespace

void stop_at_check_points() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  for (int number : kSignals) sigaddset(&action.sa_mask, number);
  // System calls under way resume as if no handler ran: a check point, not
  // a failed read, is where the command stops.
  action.sa_flags = SA_RESTART;
  for (int i = 0; i < 2; ++i) {
    struct sigaction current {};
    if (sigaction(kSignals[i], nullptr, &current) != 0 || current.sa_handler == SIG_IGN) continue;
    handled[i].store(true);
    sigaction(kSignals[i], &action, nullptr);
  }
}

int interruption_signal() noexcept {
  return watched.load()->load();
}

void throw_if_interrupted() {
  if (const int number = interruption_signal()) throw Interrupted(number);
}

const std::atomic<int>& interruption_flag() noexcept {
  return received;
}

void watch_interruption_flag(const std::atomic<int>* flag) noexcept {
  watched.store(flag);
}

}  // namespace binbow::cli
