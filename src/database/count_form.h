// Whether a BoW vector's weights are the ones Vocabulary::transform gives,
// so that they can be kept as word counts and computed again, bit for bit.
//
// Transform gives word w the weight float(word_weight(w) * count / divisor),
// in doubles, with one divisor per vector: the L1 norm of the
// word_weight(w) * count (L2 norm for L2; the word count, or 1, for the dot
// product). The inverted index (segment rows of counts) and the forward
// index (compact entries) both keep such a vector as its divisor and its
// counts, and must agree on which vectors qualify: this is the one test.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/span.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"

namespace binbow::detail {

// The weight a count form gives back: what transform computes.
inline float count_weight(double word_weight, std::uint32_t count, double divisor) noexcept {
  return static_cast<float>(word_weight * static_cast<double>(count) / divisor);
}

// 1 / divisor, for the count_weight below; 0 for a vector without a count
// form (divisor 0).
inline double inverse_divisor(double divisor) noexcept {
  return divisor > 0 ? 1.0 / divisor : 0.0;
}

// count_weight(word_weight, count, divisor) to the last bit, with a
// multiplication by `inverse` (inverse_divisor(divisor)) in place of the
// division: where many weights share a divisor (an entry's words), one
// division serves them all. word_weight × count is exact (24 by 16 bits),
// so the product with the inverse is within 3 units in the last place
// (ulps) of the quotient that transform rounds to a double. Rounding to a
// float drops 29 bits, and gives the quotient's float unless a midpoint
// between two floats (29 dropped bits of 1000...0) lies within those 3
// ulps: then, and below the normal floats, the weight is divided as
// transform does (about one weight in 2^25).
inline float count_weight(double word_weight, std::uint32_t count, double divisor,
                          double inverse) noexcept {
  const double estimate = word_weight * static_cast<double>(count) * inverse;
  std::uint64_t bits;
  std::memcpy(&bits, &estimate, sizeof bits);
  constexpr std::uint64_t kDropped = (std::uint64_t{1} << 29) - 1;
  constexpr std::uint64_t kMidpoint = std::uint64_t{1} << 28;
  constexpr std::uint64_t kGuard = 8;  // ulps, above the 3 the error can reach
  const std::uint64_t from_midpoint = (bits & kDropped) - kMidpoint + kGuard;
  if (__builtin_expect(from_midpoint <= 2 * kGuard || !(estimate >= 0x1p-126), 0))
    return count_weight(word_weight, count, divisor);
  return static_cast<float>(estimate);
}

// Finds a vector's count form, reusing its buffers from call to call.
class CountForm {
 public:
  // True when every weight of `words` is count_weight(word_weight(w), count,
  // divisor) to the last bit, for counts in [1, 65535] and one divisor; then
  // divisor() and counts() (parallel to `words`) hold them. Empty vectors,
  // words beyond the vocabulary or of weight 0 and values ≤ 0 have none.
  bool find(const Vocabulary& vocabulary, Scoring scoring, Span<BowEntry> words);
  double divisor() const noexcept { return divisor_; }
  const std::vector<std::uint32_t>& counts() const noexcept { return counts_; }
  std::uint32_t largest_count() const noexcept { return largest_count_; }

 private:
  std::vector<float> weights_;  // word_weight of each word
  std::vector<float> values_;
  std::vector<float> ratios_;  // value / word weight
  std::vector<std::uint32_t> counts_;
  double divisor_ = 0;
  std::uint32_t largest_count_ = 0;
};

}  // namespace binbow::detail
