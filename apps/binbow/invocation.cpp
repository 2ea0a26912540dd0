#include "invocation.h"

#include <atomic>
#include <cstdarg>
#include <ctime>
#include <string_view>

namespace binbow::cli {
namespace {

Invocation own;
std::atomic<const Invocation*> watched{&own};

// Characters a POSIX shell takes literally outside quotes.
bool needs_no_quotes(const std::string& argument) {
  if (argument.empty()) return false;
  for (const char c : argument) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                       std::string_view("@%_+=:,./-").find(c) != std::string_view::npos;
    if (!plain) return false;
  }
  return true;
}

}  // namespace

const Invocation& invocation() noexcept {
  return *watched.load();
}

Invocation& own_invocation() noexcept {
  return own;
}

void watch_invocation(const Invocation* invocation) noexcept {
  watched.store(invocation);
}

std::string shell_quoted(const std::vector<std::string>& arguments) {
  std::string line;
  for (const std::string& argument : arguments) {
    if (!line.empty()) line += ' ';
    if (needs_no_quotes(argument)) {
      line += argument;
      continue;
    }
    // Inside single quotes everything is literal but the quote itself,
    // which closes, is escaped and reopens: ' -> '\''.
    line += '\'';
    for (const char c : argument) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
    line += '\'';
  }
  return line;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

std::FILE* summary_stream(bool product_on_stdout) noexcept {
  if (invocation().quiet) return nullptr;
  return product_on_stdout ? stderr : stdout;
}

void print_summary(bool product_on_stdout, const char* format, ...) {
  std::FILE* stream = summary_stream(product_on_stdout);
  if (stream == nullptr) return;
  va_list arguments;
  va_start(arguments, format);
  std::vfprintf(stream, format, arguments);
  va_end(arguments);
}

void note(const char* format, ...) {
  if (invocation().quiet) return;
  va_list arguments;
  va_start(arguments, format);
  std::vfprintf(stderr, format, arguments);
  va_end(arguments);
}

}  // namespace binbow::cli
