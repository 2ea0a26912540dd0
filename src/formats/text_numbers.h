// Number parsing and printing for the text formats: std::from_chars and
// std::to_chars on byte ranges (no locale, no stream, no allocation).
#pragma once

#include <charconv>
#include <cstddef>
#include <cstdint>
#include <string>
#include <system_error>
#include <vector>

namespace binbow::detail {

inline bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

inline const char* skip_blanks(const char* p, const char* end) {
  while (p < end && is_blank(*p)) ++p;
  return p;
}

// Parses one whitespace-delimited token as a number of type T at `p` (after
// blanks); on success advances `p` past it. Fails on garbage, overflow, or a
// token that continues with something other than a blank.
template <class T>
inline bool parse_token(const char*& p, const char* end, T& value) {
  const char* start = skip_blanks(p, end);
  const auto [next, ec] = std::from_chars(start, end, value);
  if (ec != std::errc() || (next < end && !is_blank(*next))) return false;
  p = next;
  return true;
}

inline void append_text(std::vector<std::uint8_t>& out, const char* text, std::size_t size) {
  out.insert(out.end(), text, text + size);
}
inline void append_text(std::vector<std::uint8_t>& out, const std::string& text) {
  append_text(out, text.data(), text.size());
}

template <class T>
inline void append_number(std::vector<std::uint8_t>& out, T value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  append_text(out, buffer, static_cast<std::size_t>(result.ptr - buffer));
}

// The shortest decimal that reads back as exactly `value`.
inline void append_float(std::vector<std::uint8_t>& out, float value) {
  append_number(out, value);
}

}  // namespace binbow::detail
