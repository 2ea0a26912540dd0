#include "core/warnings.h"

#include <cstdio>
#include <mutex>
#include <string>
#include <utility>

#include "binbow/error.h"

namespace binbow {
namespace {

std::mutex& handler_mutex() {
  static std::mutex mutex;
  return mutex;
}

WarningHandler& handler() {
  static WarningHandler instance;
  return instance;
}

}  // namespace

void set_warning_handler(WarningHandler new_handler) {
  std::lock_guard<std::mutex> lock(handler_mutex());
  handler() = std::move(new_handler);
}

namespace detail {

void warn(const std::string& message) noexcept {
  WarningHandler current;
  {
    std::lock_guard<std::mutex> lock(handler_mutex());
    current = handler();
  }
  try {
    if (current) {
      current(message);
      return;
    }
  } catch (...) {
    // A handler that throws must not turn a committed save into a failure.
  }
  std::fprintf(stderr, "binbow: warning: %s\n", message.c_str());
}

}  // namespace detail
}  // namespace binbow
