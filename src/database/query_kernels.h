// The inner loops of a query: a query word's postings in a segment's rows
// (a stripe of entries at a time) and in the tail's group lists, summed into
// a part's scores with the scoring's term. Included by database_query.cpp
// alone; the names are internal to it.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "binbow/database.h"
#include "core/scoring.h"
#include "database/database_impl.h"

namespace binbow::detail::query {

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

// A query word's row in a segment, read a stripe of entries at a time.
struct RowCursor {
  const std::uint8_t* at;   // the next posting
  const std::uint8_t* end;  // after the row's last whole posting
  std::uint32_t entry;      // of the posting before `at` (kRowStart: none)
  std::uint32_t q;          // the query word
  float word_weight;        // a count row's word's vocabulary weight
  bool narrow;              // 1-byte gaps
  bool counts;              // a count row
};

// Where a part's scores go: indexed by entry - the part's first entry.
struct PartScores {
  EntryScore* entries;

  // Within the kSegmentSpan sums whatever `relative_entry` is (a loaded
  // file's gaps are summed before its check ends).
  void add(std::uint32_t relative_entry, double term) const {
    EntryScore& score = entries[relative_entry & (detail::kSegmentSpan - 1)];
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

// The rows of `words` in a segment, found before any is read, each row's
// start fetched (and a count row's word weight read once, not at every
// stripe): most of a query's words are rare, with short rows, and looking
// each row up only when it is read left its cache misses unhidden. The rows
// of a loaded file may be read before its check ends: a row is read as whole
// postings of its header's width (any width but 1 is 2) and kind, never
// past its end.
inline void find_rows(const detail::Segment& segment, detail::RowOrder order, Span<BowEntry> words,
                      const float* word_weights, std::vector<RowCursor>& rows) {
  const std::uint32_t* offsets = segment.offsets.data();
  const std::uint8_t* bytes = segment.bytes.data();
  const std::size_t n = words.size();
  rows.clear();
  for (std::size_t q = 0; q < n; ++q) {
    if (q + kPrefetchAhead < n)
      __builtin_prefetch(offsets + order.row(words[q + kPrefetchAhead].word));
    const std::uint32_t row = order.row(words[q].word);
    const std::uint32_t size = offsets[row + 1] - offsets[row];
    if (size == 0) continue;
    const std::uint8_t* const begin = bytes + offsets[row];
    __builtin_prefetch(begin);
    if (word_weights != nullptr) __builtin_prefetch(word_weights + words[q].word);
    rows.push_back({begin, begin + size, detail::kRowStart, static_cast<std::uint32_t>(q), 0.0f,
                    false, false});
  }
  for (RowCursor& row : rows) {
    const std::uint8_t header = *row.at;
    const std::uint8_t* const first = row.at + detail::kRowHeaderBytes;
    row.narrow = detail::header_width(header) == 1;
    row.counts = detail::header_counts(header);
    if (row.counts && word_weights != nullptr) row.word_weight = word_weights[words[row.q].word];
    const std::size_t stride =
        (row.narrow ? 1 : 2) + (row.counts ? detail::kCountBytes : detail::kWeightBytes);
    row.end = first + static_cast<std::size_t>(row.end - first) / stride * stride;
    row.at = first;
  }
}

// A segment's entries are scored a stripe at a time, each row read up to
// the stripe's last entry, so that the stripe's sums and divisors (20 bytes
// per entry; fast mode's candidate sums 4) stay in the core's L2 cache
// (512 KiB on AMD Zen 2 and 3), as a whole segment's (1.25 MiB) would not.
constexpr std::uint32_t kStripeEntries = 8192;

// Calls read(cursor, until) for every unfinished row, stripe after stripe,
// `until` being the stripe's last entry (relative to the segment; `last`
// for the final stripe), then done(first, end) with the stripe's entries.
// read() leaves the cursor after the postings it read.
template <class Read, class Done>
void read_in_stripes(std::vector<RowCursor>& rows, std::uint32_t entry_bound, std::uint32_t last,
                     Read&& read, Done&& done) {
  for (std::uint32_t first = 0;; first += kStripeEntries) {
    const std::uint32_t stripe_last = first + (kStripeEntries - 1);
    const bool final_stripe = stripe_last >= entry_bound || stripe_last >= last;
    const std::uint32_t until = final_stripe ? last : stripe_last;
    std::size_t unfinished = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (i + kPrefetchAhead < rows.size()) {
        const RowCursor& ahead = rows[i + kPrefetchAhead];
        // Up to 4 lines: a stripe of a large segment reads an eighth of a
        // row, and most rows are short (rare words).
        for (const std::uint8_t* line = ahead.at; line < ahead.end && line < ahead.at + 256;
             line += 64)
          __builtin_prefetch(line);
      }
      RowCursor row = rows[i];
      read(row, until);
      if (row.at != row.end) rows[unfinished++] = row;
    }
    rows.resize(unfinished);
    done(first, final_stripe ? entry_bound + 1 : stripe_last + 1);
    if (final_stripe) return;
  }
}

// A row's postings at their fixed stride, from the cursor until an entry
// passes `until`: the entries are a running sum of the gaps. Calls
// add(entry, count) for a count row, add(entry, weight) for the others.
template <std::size_t kWidth, bool kCounts, class Add>
inline void read_row(RowCursor& row, std::uint32_t until, const Add& add) {
  constexpr std::size_t kStride = kWidth + (kCounts ? detail::kCountBytes : detail::kWeightBytes);
  const std::uint8_t* at = row.at;
  std::uint32_t entry = row.entry;
  for (; at != row.end; at += kStride) {
    const std::uint32_t next = entry + detail::read_gap<kWidth>(at) + 1;
    if (next > until) break;
    entry = next;
    if constexpr (kCounts)
      add(entry, std::uint32_t{at[kWidth]});
    else
      add(entry, detail::read_weight(at + kWidth));
  }
  row.at = at;
  row.entry = entry;
}

// Reads a row with add_weight(entry, weight) or add_count(entry, count).
template <class AddWeight, class AddCount>
inline void read_any_row(RowCursor& row, std::uint32_t until, const AddWeight& add_weight,
                         const AddCount& add_count) {
  if (row.counts) {
    if (row.narrow)
      read_row<1, true>(row, until, add_count);
    else
      read_row<2, true>(row, until, add_count);
  } else if (row.narrow) {
    read_row<1, false>(row, until, add_weight);
  } else {
    read_row<2, false>(row, until, add_weight);
  }
}

// Every term of the query's words for a segment's entries, in word order for
// each entry. A count row's weight is computed from the count, as the
// entry's was when it was added; its divisor is looked up at most at
// `entry_bound` (the segment's last entry): a row of an unchecked file may
// reach past it. Entries are increasing within a row, so `last_entry` cuts
// it short.
template <class Term>
void accumulate_segment(const detail::Segment& segment, detail::RowOrder order, Span<BowEntry> bow,
                        EntryId last_entry, const detail::SegmentWeights& weights,
                        PartScores scores, std::vector<RowCursor>& rows) {
  const bool cut = last_entry < segment.end_entry - 1;
  const std::uint32_t last = cut ? last_entry - segment.first_entry : detail::kRowStart;
  const std::uint32_t entry_bound = segment.end_entry - segment.first_entry - 1;
  find_rows(segment, order, bow, weights.word_weights, rows);
  read_in_stripes(
      rows, entry_bound, last,
      [&](RowCursor& row, std::uint32_t until) {
        const Term term{bow[row.q].value};
        const detail::RowWeights row_weights{row.word_weight, weights.divisors};
        read_any_row(
            row, until, [&](std::uint32_t entry, float weight) { scores.add(entry, term(weight)); },
            [&](std::uint32_t entry, std::uint32_t count) {
              scores.add(entry, term(row_weights.weight(std::min(entry, entry_bound), count)));
            });
      },
      [](std::uint32_t, std::uint32_t) {});
}

// What a query reads of the index (Database::Impl is private).
struct IndexView {
  const std::vector<std::unique_ptr<detail::Segment>>& segments;
  const detail::TailList* tail_lists;
  const detail::PostingArena& arena;
  unsigned tail_list_shift;
  unsigned high_bits;
  detail::RowOrder row_order;
  std::size_t tail_postings;
  EntryId tail_first_entry;
  const std::uint8_t* alive;
  std::size_t entry_count;
  const detail::ForwardIndex* forward;  // built for fast queries
  const float* word_weights;            // the vocabulary's; null over word ids
  const double* divisors;               // Database::Impl::divisors
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

// A query word's tail list holds the postings of up to 2^high_bits words,
// in increasing entry order: the word's own are picked out by the key's
// low bits, its row among the list's.
template <class Term>
void accumulate_tail(const IndexView& index, Span<BowEntry> bow, EntryId last_entry,
                     PartScores scores) {
  const detail::TailList* lists = index.tail_lists;
  const detail::RowOrder order = index.row_order;
  const unsigned shift = index.tail_list_shift;
  const unsigned bits = index.high_bits;
  const std::uint32_t mask = (1u << bits) - 1;
  const std::uint64_t key_end = (std::uint64_t{last_entry} - index.tail_first_entry + 1) << bits;
  const std::size_t n = bow.size();
  const BowEntry* query = bow.data();
  for (std::size_t q = 0; q < n; ++q) {
    if (q + 2 * kPrefetchAhead < n)
      __builtin_prefetch(lists + (detail::group_of(query[q + 2 * kPrefetchAhead].word) >> shift));
    if (q + kPrefetchAhead < n) {
      // The whole list is read: fetch up to 2 KiB of it, not just its start.
      const detail::TailList ahead =
          lists[detail::group_of(query[q + kPrefetchAhead].word) >> shift];
      if (ahead.size != 0) {
        const auto* block = reinterpret_cast<const char*>(index.arena.at(ahead.block));
        const std::size_t bytes =
            std::min<std::size_t>(ahead.size, 256) * sizeof(detail::TailPosting);
        for (std::size_t b = 0; b < bytes; b += 64) __builtin_prefetch(block + b);
      }
    }
    const WordId word = query[q].word;
    const std::uint32_t l = detail::group_of(word) >> shift;
    const detail::TailList list = lists[l];
    if (list.size == 0) continue;
    const detail::TailPosting* postings = index.arena.at(list.block);
    const Term term{query[q].value};
    const std::uint32_t row = order.row(word) - order.group_start(l << shift);
    for_each_of_word(postings, list.size, mask, row, [&](std::uint32_t i) {
      const std::uint32_t key = postings[i].key;
      if (key >= key_end) return false;
      scores.add(key >> bits, term(postings[i].weight));
      return true;
    });
  }
}

}  // namespace binbow::detail::query
