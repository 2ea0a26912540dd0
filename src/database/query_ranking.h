// The best results and the best candidates of a query, kept as they are
// offered: most offers cost one comparison. Included by database_query.cpp
// alone.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "binbow/database.h"
#include "core/scoring.h"
#include "database/query_kernels.h"

namespace binbow::detail::query {

// A fast query's candidate: its sum over the rare words, signed so that
// larger is better.
struct Candidate {
  float key;
  EntryId entry;
};
struct BetterCandidate {
  bool operator()(const Candidate& a, const Candidate& b) const {
    return a.key != b.key ? a.key > b.key : a.entry < b.entry;
  }
};

// A worker's best candidates of the parts it searched: offers above the
// threshold are appended, and when there are twice `keep` the best `keep`
// are selected and the threshold raised to the worst of them, so that an
// offer costs O(1) on average and most cost one comparison.
class BestCandidates {
 public:
  void reset(std::size_t keep) {
    kept_.clear();
    keep_ = keep;
    threshold_ = 0.0f;
  }

  // Whether a candidate with this key may be kept: a positive sum at least
  // the threshold (ties are left to BetterCandidate: entry order).
  bool may_keep(float key) const { return key >= threshold_ && key > 0.0f; }

  void offer(const Candidate& candidate) {
    kept_.push_back(candidate);
    if (kept_.size() == 2 * keep_) select();
  }

  // The best `keep` of those offered (all, if fewer), in no order.
  std::vector<Candidate>& best() {
    select();
    return kept_;
  }

 private:
  void select() {
    if (kept_.size() <= keep_) return;
    const auto worst_kept = kept_.begin() + static_cast<std::ptrdiff_t>(keep_ - 1);
    std::nth_element(kept_.begin(), worst_kept, kept_.end(), BetterCandidate{});
    threshold_ = worst_kept->key;
    kept_.resize(keep_);
  }

  std::vector<Candidate> kept_;
  std::size_t keep_ = 1;
  float threshold_ = 0.0f;
};

// Orders best first, then by entry id. A NaN score (only from vectors with
// negative values) ranks last, so the order stays a strict weak ordering.
struct BetterResult {
  bool lower_is_better;

  double key(double score) const {
    if (std::isnan(score)) return lower_is_better ? INFINITY : -INFINITY;
    return score;
  }
  bool operator()(const QueryResult& a, const QueryResult& b) const {
    const double ka = key(a.score);
    const double kb = key(b.score);
    if (ka != kb) return lower_is_better ? ka < kb : ka > kb;
    return a.entry < b.entry;
  }
};

// The best `keep` results offered so far: a heap whose front is the worst of
// them, so that most entries cost one comparison. Its room is reserved up
// front, so offering never throws.
class BestResults {
 public:
  // With `minimums`, the sums are MinimumTerm's.
  BestResults(Scoring scoring, bool minimums, double base, std::size_t keep,
              std::vector<QueryResult>& storage)
      : scoring_(scoring),
        minimums_(minimums),
        base_(base),
        keep_(keep),
        better_{scoring == Scoring::kKL},
        results_(storage) {
    results_.clear();
    results_.reserve(keep);
  }

  // Offers the live entries of a part whose scores are done, and zeroes
  // their sums and counts for the next part. Unchecked postings may have
  // summed past the part's span (damaged gaps): those sums are zeroed too,
  // so that no later query, of any database, starts from them.
  void take_part(EntryId first, std::size_t span, PartScores scores, const std::uint8_t* alive,
                 bool unchecked) {
    for (std::size_t r = 0; r < span; ++r) {
      EntryScore& score = scores.entries[r];
      if (score.shared == 0) continue;
      if (alive[first + r] != 0)
        offer({static_cast<EntryId>(first + r), finish(score.sum), score.shared});
      score = {};
    }
    if (unchecked)
      std::fill(scores.entries + span, scores.entries + detail::kSegmentSpan, EntryScore{});
  }

  // An entry's result from its sum of terms.
  QueryResult result(EntryId entry, double sum, std::uint32_t shared) const {
    return {entry, finish(sum), shared};
  }
  // Offers every result another BestResults kept.
  void take_results(const BestResults& other) {
    for (const QueryResult& result : other.results_) offer(result);
  }

  void offer(const QueryResult& result) {
    if (results_.size() < keep_) {
      results_.push_back(result);
      if (results_.size() == keep_) std::make_heap(results_.begin(), results_.end(), better_);
    } else if (better_(result, results_.front())) {
      std::pop_heap(results_.begin(), results_.end(), better_);
      results_.back() = result;
      std::push_heap(results_.begin(), results_.end(), better_);
    }
  }

  // Best first.
  std::vector<QueryResult> sorted() {
    std::sort(results_.begin(), results_.end(), better_);
    return {results_.begin(), results_.end()};
  }

 private:
  double finish(double sum) const {
    return minimums_ ? detail::l1_score_of_minimums(sum)
                     : detail::finish_score(scoring_, sum, base_);
  }

  Scoring scoring_;
  bool minimums_;
  double base_;
  std::size_t keep_;
  BetterResult better_;
  std::vector<QueryResult>& results_;
};

}  // namespace binbow::detail::query
