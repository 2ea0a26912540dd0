#include "vision/natural_order.h"

#include <cctype>
#include <cstddef>

namespace binbow::vision {
namespace {

bool is_digit(char c) {
  return std::isdigit(static_cast<unsigned char>(c)) != 0;
}
int lower(char c) {
  return std::tolower(static_cast<unsigned char>(c));
}

// <0, 0, >0 comparing a[i..] and b[j..] naturally; no tie-break on exact text.
int compare_natural(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (is_digit(a[i]) && is_digit(b[j])) {
      while (i < a.size() && a[i] == '0') ++i;
      while (j < b.size() && b[j] == '0') ++j;
      std::size_t end_a = i, end_b = j;
      while (end_a < a.size() && is_digit(a[end_a])) ++end_a;
      while (end_b < b.size() && is_digit(b[end_b])) ++end_b;
      const std::size_t length_a = end_a - i, length_b = end_b - j;
      if (length_a != length_b) return length_a < length_b ? -1 : 1;
      for (; i < end_a; ++i, ++j) {
        if (a[i] != b[j]) return a[i] < b[j] ? -1 : 1;
      }
      continue;
    }
    const int ca = lower(a[i]), cb = lower(b[j]);
    if (ca != cb) return ca < cb ? -1 : 1;
    ++i;
    ++j;
  }
  if (i < a.size()) return 1;
  if (j < b.size()) return -1;
  return 0;
}

}  // namespace

bool natural_less(const std::string& a, const std::string& b) {
  const int order = compare_natural(a, b);
  if (order != 0) return order < 0;
  return a < b;
}

}  // namespace binbow::vision
