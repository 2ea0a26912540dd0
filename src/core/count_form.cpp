#include "core/count_form.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace binbow::detail {

// The counts are the weights over the smallest weight per word weight,
// rounded; the divisor is the norm transform would have divided by, else 1
// (the dot product without normalisation). The form is kept only if it gives
// back every weight exactly.
bool CountForm::find(const Vocabulary& vocabulary, Scoring scoring, Span<BowEntry> words) {
  const std::size_t n = words.size();
  if (n == 0 || words[n - 1].word >= vocabulary.word_count()) return false;
  weights_.resize(n);
  counts_.resize(n);
  double smallest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const double weight = vocabulary.word_weight(words[i].word);
    weights_[i] = weight;
    if (!(weight > 0) || !(words[i].value > 0)) return false;
    smallest = std::min(smallest, static_cast<double>(words[i].value) / weight);
  }
  double norms[2] = {0, 1};
  std::uint32_t largest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double count = std::round(static_cast<double>(words[i].value) / weights_[i] / smallest);
    if (!(count >= 1 && count <= 0xFFFF)) return false;
    counts_[i] = static_cast<std::uint32_t>(count);
    largest = std::max(largest, counts_[i]);
    const double raw = weights_[i] * count;
    norms[0] += scoring == Scoring::kL2 ? raw * raw : std::fabs(raw);
  }
  if (scoring == Scoring::kL2) norms[0] = std::sqrt(norms[0]);
  if (scoring == Scoring::kDotProduct) norms[0] = static_cast<double>(n);
  for (double divisor : norms) {
    bool exact = true;
    for (std::size_t i = 0; i < n && exact; ++i) {
      const float weight = count_weight(weights_[i], counts_[i], divisor);
      exact = std::memcmp(&weight, &words[i].value, sizeof weight) == 0;
    }
    if (!exact) continue;
    divisor_ = divisor;
    largest_count_ = largest;
    return true;
  }
  return false;
}

}  // namespace binbow::detail
