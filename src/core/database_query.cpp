// Queries through the inverted index: every part of the index (segment or
// tail) is scored in turn into per-thread sums, and its entries offered to
// the best results.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "binbow/database.h"
#include "core/database_impl.h"
#include "core/scoring.h"

namespace binbow {

namespace {

// Per-thread buffers reused by every query. A query scores one part of the
// index at a time (a segment or the tail: at most kSegmentSpan consecutive
// entries), so its sums and shared-word counts fit in the core's cache
// (768 KiB) whatever the database's size; both are all zero between parts.
// An entry's sum and count are packed together (12 bytes), so that a posting
// touches one cache line, not two: 4% faster queries than two arrays.
#pragma pack(push, 4)
struct EntryScore {
  double sum;
  std::uint32_t shared;
};
#pragma pack(pop)
static_assert(sizeof(EntryScore) == 12);

struct QueryScratch {
  std::vector<EntryScore> scores;
  std::vector<QueryResult> best;
};

thread_local QueryScratch scratch;

// Where a part's scores go: indexed by entry - the part's first entry.
struct PartScores {
  EntryScore* entries;

  void add(std::uint32_t relative_entry, double term) const {
    EntryScore& score = entries[relative_entry];
    score.sum += term;
    ++score.shared;
  }
};

// A query word's term with each posting: DBoW2's for the scoring, or the
// minimum of the two values for L1 where detail::l1_terms_are_minimums.
template <Scoring kScoring>
struct ScoringTerm {
  double value;
  double operator()(float weight) const { return detail::score_term(kScoring, value, weight); }
};
struct MinimumTerm {
  float value;
  double operator()(float weight) const { return std::min(value, weight); }
};

// Posting lists are scattered in memory: the rows of words a few steps
// ahead are prefetched so that their cache misses overlap.
constexpr std::size_t kPrefetchAhead = 8;

// Entries are increasing within a row, so `last_entry` cuts it short.
template <class Term>
void accumulate_segment(const detail::Segment& segment, detail::RowOrder order,
                        const BowVector& bow, EntryId last_entry, PartScores scores) {
  const std::uint32_t* offsets = segment.offsets.data();
  const std::uint16_t* entries = segment.entries16.data();
  const float* weights = segment.weights.data();
  const bool cut = last_entry < segment.end_entry - 1;
  const auto last = static_cast<std::uint16_t>(cut ? last_entry - segment.first_entry : 0);
  const std::size_t n = bow.size();
  const BowEntry* query = bow.begin();
  for (std::size_t q = 0; q < n; ++q) {
    if (q + 2 * kPrefetchAhead < n)
      __builtin_prefetch(offsets + order.row(query[q + 2 * kPrefetchAhead].word));
    if (q + kPrefetchAhead < n) {
      const std::uint32_t begin = offsets[order.row(query[q + kPrefetchAhead].word)];
      __builtin_prefetch(entries + begin);
      __builtin_prefetch(weights + begin);
    }
    const std::uint32_t row = order.row(query[q].word);
    const std::uint32_t begin = offsets[row];
    std::uint32_t end = offsets[row + 1];
    if (cut)
      end = static_cast<std::uint32_t>(std::upper_bound(entries + begin, entries + end, last) -
                                       entries);
    const Term term{query[q].value};
    for (std::uint32_t i = begin; i < end; ++i) scores.add(entries[i], term(weights[i]));
  }
}

// What a query reads of the index (Database::Impl is private).
struct IndexView {
  const std::vector<std::unique_ptr<detail::Segment>>& segments;
  const detail::TailList* tail_lists;
  const detail::PostingArena& arena;
  unsigned high_bits;
  detail::RowOrder row_order;
  std::size_t tail_postings;
  EntryId tail_first_entry;
  const std::uint8_t* alive;
  std::size_t entry_count;
};

// Calls take(i) for the postings of a group list whose key has the given
// low bits (the postings of one word), in order, until take returns false.
// Four keys are compared at once: a word's postings are a small part of its
// group's.
template <typename Take>
inline void for_each_of_word(const detail::TailPosting* postings, std::uint32_t size,
                             std::uint32_t mask, std::uint32_t low, Take&& take) {
  std::uint32_t i = 0;
#if defined(__SSE2__)
  const __m128i masks = _mm_set1_epi32(static_cast<int>(mask));
  const __m128i lows = _mm_set1_epi32(static_cast<int>(low));
  for (; i + 4 <= size; i += 4) {
    const __m128 a = _mm_loadu_ps(reinterpret_cast<const float*>(postings + i));
    const __m128 b = _mm_loadu_ps(reinterpret_cast<const float*>(postings + i + 2));
    const __m128i keys = _mm_castps_si128(_mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)));
    unsigned hits = static_cast<unsigned>(
        _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(keys, masks), lows))));
    while (hits != 0) {
      if (!take(i + static_cast<std::uint32_t>(__builtin_ctz(hits)))) return;
      hits &= hits - 1;
    }
  }
#endif
  for (; i < size; ++i)
    if ((postings[i].key & mask) == low && !take(i)) return;
}

// A query word's group list holds the postings of up to 2^high_bits words,
// in increasing entry order: the word's own are picked out by their high
// bits.
template <class Term>
void accumulate_tail(const IndexView& index, const BowVector& bow, EntryId last_entry,
                     PartScores scores) {
  const detail::TailList* lists = index.tail_lists;
  const unsigned bits = index.high_bits;
  const std::uint32_t mask = (1u << bits) - 1;
  const std::uint64_t key_end = (std::uint64_t{last_entry} - index.tail_first_entry + 1) << bits;
  const std::size_t n = bow.size();
  const BowEntry* query = bow.begin();
  for (std::size_t q = 0; q < n; ++q) {
    if (q + 2 * kPrefetchAhead < n)
      __builtin_prefetch(lists + detail::group_of(query[q + 2 * kPrefetchAhead].word));
    if (q + kPrefetchAhead < n) {
      // The whole list (up to 2 KiB) is read: fetch it all, not its start.
      const detail::TailList ahead = lists[detail::group_of(query[q + kPrefetchAhead].word)];
      if (ahead.size != 0) {
        const auto* block = reinterpret_cast<const char*>(index.arena.at(ahead.block));
        const std::size_t bytes =
            std::min<std::size_t>(ahead.size, 256) * sizeof(detail::TailPosting);
        for (std::size_t b = 0; b < bytes; b += 64) __builtin_prefetch(block + b);
      }
    }
    const WordId word = query[q].word;
    const detail::TailList list = lists[detail::group_of(word)];
    if (list.size == 0) continue;
    const detail::TailPosting* postings = index.arena.at(list.block);
    const Term term{query[q].value};
    for_each_of_word(postings, list.size, mask, word >> detail::kGroupBits, [&](std::uint32_t i) {
      const std::uint32_t key = postings[i].key;
      if (key >= key_end) return false;
      scores.add(key >> bits, term(postings[i].weight));
      return true;
    });
  }
}

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
  // their sums and counts for the next part.
  void take_part(EntryId first, std::size_t span, PartScores scores, const std::uint8_t* alive) {
    for (std::size_t r = 0; r < span; ++r) {
      EntryScore& score = scores.entries[r];
      if (score.shared == 0) continue;
      if (alive[first + r] != 0)
        offer({static_cast<EntryId>(first + r), finish(score.sum), score.shared});
      score = {};
    }
  }

  // Best first.
  std::vector<QueryResult> sorted() {
    std::sort(results_.begin(), results_.end(), better_);
    return {results_.begin(), results_.end()};
  }

 private:
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

// Every term is computed and summed exactly as Vocabulary::score does (or,
// for MinimumTerm, as its exact equal), in the same order (increasing word
// id), so scores agree to the last bit: each entry lives in one segment or in
// the tail, whose pass visits the query's words in order.
template <class Term>
void score_parts(const IndexView& index, const BowVector& bow, EntryId last_entry,
                 PartScores scores, BestResults& best) {
  for (const auto& segment : index.segments) {
    if (segment->first_entry > last_entry) return;
    accumulate_segment<Term>(*segment, index.row_order, bow, last_entry, scores);
    best.take_part(segment->first_entry,
                   std::min<std::size_t>(segment->end_entry, std::size_t{last_entry} + 1) -
                       segment->first_entry,
                   scores, index.alive);
  }
  if (index.tail_postings > 0 && index.tail_first_entry <= last_entry) {
    accumulate_tail<Term>(index, bow, last_entry, scores);
    best.take_part(index.tail_first_entry,
                   std::min<std::size_t>(index.entry_count, std::size_t{last_entry} + 1) -
                       index.tail_first_entry,
                   scores, index.alive);
  }
}

void score_parts(Scoring scoring, bool minimums, const IndexView& index, const BowVector& bow,
                 EntryId last_entry, PartScores scores, BestResults& best) {
  switch (scoring) {
    case Scoring::kL1:
      if (minimums) return score_parts<MinimumTerm>(index, bow, last_entry, scores, best);
      return score_parts<ScoringTerm<Scoring::kL1>>(index, bow, last_entry, scores, best);
    case Scoring::kL2:
      return score_parts<ScoringTerm<Scoring::kL2>>(index, bow, last_entry, scores, best);
    case Scoring::kChiSquare:
      return score_parts<ScoringTerm<Scoring::kChiSquare>>(index, bow, last_entry, scores, best);
    case Scoring::kKL:
      return score_parts<ScoringTerm<Scoring::kKL>>(index, bow, last_entry, scores, best);
    case Scoring::kBhattacharyya:
      return score_parts<ScoringTerm<Scoring::kBhattacharyya>>(index, bow, last_entry, scores,
                                                               best);
    case Scoring::kDotProduct:
      return score_parts<ScoringTerm<Scoring::kDotProduct>>(index, bow, last_entry, scores, best);
  }
}

}  // namespace

std::vector<QueryResult> Database::query(const BowVector& bow, std::size_t max_results,
                                         EntryId max_entry_id) const {
  if (!impl_->over_word_ids) detail::check_bow_words(bow, impl_->vocabulary, "Database::query");
  detail::check_bow_values(bow, "Database::query");
  std::vector<QueryResult> results;
  if (bow.empty() || max_results == 0) return results;
  const Scoring scoring = impl_->scoring;
  const double base = detail::score_base(scoring, bow);

  std::shared_lock lock(impl_->mutex);
  // Over word ids, words beyond the capacity are in no entry yet: the index
  // is searched for the others (base() above still counts them, for KL).
  BowVector indexed_words;
  const BowVector* searched = &bow;
  if (impl_->over_word_ids && bow[bow.size() - 1].word >= impl_->word_capacity) {
    const auto end =
        std::lower_bound(bow.begin(), bow.end(), impl_->word_capacity,
                         [](const BowEntry& e, std::size_t capacity) { return e.word < capacity; });
    indexed_words = BowVector(std::vector<BowEntry>(bow.begin(), end));
    if (indexed_words.empty()) return results;
    searched = &indexed_words;
  }
  const std::size_t entry_count = impl_->alive.size();
  if (impl_->live_entries == 0) return results;
  QueryScratch& buffers = scratch;
  if (buffers.scores.size() < detail::kSegmentSpan) buffers.scores.resize(detail::kSegmentSpan);
  const EntryId last_entry = std::min<EntryId>(max_entry_id, static_cast<EntryId>(entry_count - 1));
  const IndexView index{impl_->segments,         impl_->tail_lists.data(), impl_->arena,
                        impl_->high_bits,        impl_->row_order,         impl_->tail_postings,
                        impl_->tail_first_entry, impl_->alive.data(),      entry_count};
  const bool minimums =
      scoring == Scoring::kL1 &&
      detail::l1_terms_are_minimums(impl_->values, detail::value_range(*searched));
  BestResults best(scoring, minimums, base, std::min(max_results, impl_->live_entries),
                   buffers.best);
  score_parts(scoring, minimums, index, *searched, last_entry, PartScores{buffers.scores.data()},
              best);
  lock.unlock();
  return best.sorted();
}

}  // namespace binbow
