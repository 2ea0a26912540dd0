#include "database/count_form.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace binbow::detail {

// The counts are the weights over the smallest weight per word weight,
// rounded; the divisor is the norm transform would have divided by, else 1
// (the dot product without normalisation). The form is kept only if it gives
// back every weight exactly, so the counts may be estimated in floats (within
// 2^-21 relatively, far from a wrong rounding for counts below 65,536): this
// test runs on every add.
bool CountForm::find(const Vocabulary& vocabulary, Scoring scoring, Span<BowEntry> words) {
  const std::size_t n = words.size();
  if (n == 0 || words[n - 1].word >= vocabulary.word_count()) return false;
  weights_.resize(n);
  values_.resize(n);
  ratios_.resize(n);
  counts_.resize(n);
  float* const weights = weights_.data();
  float* const values = values_.data();
  float* const ratios = ratios_.data();
  const float* const word_weights = detail::word_weights(vocabulary);
  for (std::size_t i = 0; i < n; ++i) {
    weights[i] = word_weights[words[i].word];
    values[i] = words[i].value;
  }
  // Branch-free, so that these loops run in vector registers.
  std::uint32_t positive = 1;
  float smallest = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    positive &=
        static_cast<std::uint32_t>(weights[i] > 0) & static_cast<std::uint32_t>(values[i] > 0);
    ratios[i] = values[i] / weights[i];
    smallest = std::min(smallest, ratios[i]);
  }
  if (positive == 0 || !(smallest > 0) || !std::isfinite(smallest)) return false;
  const float scale = 1 / smallest;
  std::uint32_t* const counts = counts_.data();
  std::uint32_t in_range = 1;
  for (std::size_t i = 0; i < n; ++i) {
    const float count = std::min(ratios[i] * scale + 0.5f, 65536.0f);
    in_range &= static_cast<std::uint32_t>(count >= 1) & static_cast<std::uint32_t>(count < 65536);
    counts[i] = static_cast<std::uint32_t>(static_cast<std::int32_t>(count));
  }
  if (in_range == 0) return false;
  // In word order, as transform sums them.
  double norms[2] = {0, 1};
  std::uint32_t largest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double raw = static_cast<double>(weights[i]) * counts[i];
    norms[0] += scoring == Scoring::kL2 ? raw * raw : raw;
    largest = std::max(largest, counts[i]);
  }
  if (scoring == Scoring::kL2) norms[0] = std::sqrt(norms[0]);
  if (scoring == Scoring::kDotProduct) norms[0] = static_cast<double>(n);
  for (double divisor : norms) {
    std::uint32_t differ = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const float weight = count_weight(weights[i], counts[i], divisor);
      std::uint32_t a, b;
      std::memcpy(&a, &weight, 4);
      std::memcpy(&b, values + i, 4);
      differ |= a ^ b;
    }
    if (differ != 0) continue;
    divisor_ = divisor;
    largest_count_ = largest;
    return true;
  }
  return false;
}

}  // namespace binbow::detail
