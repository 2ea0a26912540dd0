// DBoW2's six scores written as a sum over the words two BoW vectors share,
// so that the same arithmetic serves a pairwise score and an inverted-index
// query (which only ever sees shared words).
//
//   score(q, e) = finish(Σ_{shared words} term(q_i, e_i), base(q))
//
// base(q) is 0 except for KL, whose sum also runs over the query's words that
// the entry lacks (DBoW2 charges them v·(log v − log ε)).
#pragma once

#include <algorithm>
#include <cfloat>
#include <cmath>

#include "binbow/bow_vector.h"
#include "binbow/types.h"

namespace binbow::detail {

inline const double kLogEpsilon = std::log(DBL_EPSILON);

inline double kl_missing_term(double v) {
  return v * (std::log(v) - kLogEpsilon);
}

inline double score_term(Scoring scoring, double v, double w) {
  switch (scoring) {
    case Scoring::kL1:
      return std::fabs(v - w) - std::fabs(v) - std::fabs(w);
    case Scoring::kL2:
    case Scoring::kDotProduct:
      return v * w;
    case Scoring::kChiSquare:
      return v + w != 0.0 ? v * w / (v + w) : 0.0;
    case Scoring::kKL:
      return v != 0.0 && w != 0.0 ? v * std::log(v / w) - kl_missing_term(v) : 0.0;
    case Scoring::kBhattacharyya:
      return std::sqrt(v * w);
  }
  return 0.0;
}

// Query-only part of the score (non-zero for KL only).
inline double score_base(Scoring scoring, const BowVector& query) {
  if (scoring != Scoring::kKL) return 0.0;
  double base = 0.0;
  for (const BowEntry& e : query)
    if (e.value != 0.0f) base += kl_missing_term(e.value);
  return base;
}

inline double finish_score(Scoring scoring, double shared_sum, double base) {
  switch (scoring) {
    case Scoring::kL1:
      return -shared_sum / 2.0;
    case Scoring::kL2:
      return shared_sum >= 1.0 ? 1.0 : 1.0 - std::sqrt(1.0 - shared_sum);
    case Scoring::kChiSquare:
      return 2.0 * shared_sum;
    case Scoring::kKL:
      return base + shared_sum;
    case Scoring::kBhattacharyya:
    case Scoring::kDotProduct:
      return shared_sum;
  }
  return shared_sum;
}

// What the values of an index (or of a query) span: the smallest positive,
// the largest, and whether any is negative.
struct ValueRange {
  float min_positive = INFINITY;
  float max = 0.0f;
  bool negative = false;

  void include(float value) noexcept {
    negative = negative || value < 0.0f;
    if (value > 0.0f) min_positive = std::min(min_positive, value);
    max = std::max(max, value);
  }
  void include(const ValueRange& other) noexcept {
    negative = negative || other.negative;
    min_positive = std::min(min_positive, other.min_positive);
    max = std::max(max, other.max);
  }
};

inline ValueRange value_range(const BowVector& bow) noexcept {
  ValueRange range;
  for (const BowEntry& e : bow) range.include(e.value);
  return range;
}

// L1's term |v - w| - |v| - |w|, computed in double from floats, is exactly
// -2 min(v, w) when v, w >= 0 are less than 2^29 apart by ratio: v - w and
// w - 2v then span at most 53 bits, so each step is exact. Scaling by -2 is
// exact too, so a query may sum the minimums and get DBoW2's score to the
// last bit, with fewer instructions per posting (see l1_score_of_minimums).
inline bool l1_terms_are_minimums(const ValueRange& index, const ValueRange& query) noexcept {
  if (index.negative || query.negative) return false;
  const double smallest = std::min(index.min_positive, query.min_positive);
  const double largest = std::max(index.max, query.max);
  return largest < smallest * 0x1p29;  // true too when no value is positive
}

// finish_score(kL1, -2 sum, 0) for a sum of minimums: the sum itself, but
// -0.0 for 0, as DBoW2's terms (all +0.0 then) give.
inline double l1_score_of_minimums(double sum) noexcept {
  return sum != 0.0 ? sum : -0.0;
}

}  // namespace binbow::detail
