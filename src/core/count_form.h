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
