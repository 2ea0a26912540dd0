// Segments: the tail frozen into compact posting lists, merged as they
// multiply, compacted when removals leave holes.
#include "binbow/database.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <utility>

#include "binbow/error.h"
#include "database/database_impl.h"

namespace binbow {

void Database::Impl::freeze_tail_if_full() {
  if (tail_postings < segment_postings && alive.size() - tail_first_entry < detail::kSegmentSpan)
    return;
  try {
    freeze_tail();
    merge_segments_if_many();
  } catch (...) {
    // Out of memory for the new segment: the index stays valid as it is,
    // and the add that got here has succeeded.
  }
}

void Database::Impl::merge_segments_if_many() {
  for (;;) {
    const std::size_t n = segments.size();
    if (n < detail::kSegmentFanIn) return;
    const unsigned level = segments[n - 1]->level;
    if (level == detail::kLoadedLevel) return;
    for (std::size_t i = n - detail::kSegmentFanIn; i < n; ++i)
      if (segments[i]->level != level) return;
    // A merged segment spans at most kSegmentSpan ids, so that a query's
    // sums for it stay in cache: the oldest of these segments that fit
    // together merge, if at least two do.
    const std::size_t begin = n - detail::kSegmentFanIn;
    std::size_t end = begin + 1;
    while (end < n &&
           segments[end]->end_entry - segments[begin]->first_entry <= detail::kSegmentSpan)
      ++end;
    if (end - begin < 2) return;
    merge_segments(begin, end);
  }
}

namespace {

// Row by row, the rows of the segments [begin, end), oldest first: entries
// stay in increasing order, every source is read sequentially. Merged
// segments and their sources span at most kSegmentSpan ids. Returns the
// bytes written.
std::size_t merge_rows(const std::unique_ptr<detail::Segment>* begin,
                       const std::unique_ptr<detail::Segment>* end, detail::Segment& merged,
                       const detail::SegmentWeights& weights) {
  // The sources' arrays, read once: the stores below could alias their fields.
  // merge_segments_if_many merges at most kSegmentFanIn segments.
  struct Source {
    const std::uint32_t* offsets;
    const std::uint8_t* bytes;
    std::uint32_t shift;  // first_entry - merged.first_entry
  };
  Source sources[detail::kSegmentFanIn];
  std::size_t source_count = 0;
  for (auto source = begin; source != end; ++source, ++source_count) {
    const detail::Segment& s = **source;
    sources[source_count] = {s.offsets.data(), s.bytes.data(), s.first_entry - merged.first_entry};
  }
  std::uint8_t* const out_begin = merged.bytes.data();
  std::uint8_t* out = out_begin;
  const std::size_t rows = merged.offsets.size() - 1;
  std::uint32_t* offsets = merged.offsets.data();
  offsets[0] = 0;
  detail::RowOrder::for_each_row(rows, [&](std::uint32_t r, WordId word) {
    std::uint32_t last = detail::kRowStart;  // relative to merged.first_entry
    detail::RowWriter row(out, weights, word);
    for (std::size_t k = 0; k < source_count; ++k) {
      const Source& s = sources[k];
      detail::for_each_posting(s.bytes + s.offsets[r], s.bytes + s.offsets[r + 1],
                               [&](std::uint32_t relative, detail::PostingValue value) {
                                 const std::uint32_t entry = s.shift + relative;
                                 row.put(entry - last - 1, value);
                                 last = entry;
                               });
    }
    out = row.finish();
    offsets[r + 1] = static_cast<std::uint32_t>(out - out_begin);
  });
  return static_cast<std::size_t>(out - out_begin);
}

}  // namespace

void Database::Impl::merge_segments(std::size_t begin, std::size_t end) {
  // Rows are written in RowWriter's slots, then narrowed: room for that,
  // then the block shrinks to what was written.
  std::size_t postings = 0;
  for (std::size_t i = begin; i < end; ++i) postings += segments[i]->postings();
  const std::size_t rows = segments[begin]->offsets.size() - 1;
  const std::size_t bytes = postings * detail::kWriterSlotBytes + std::min(postings, rows);
  if (bytes > std::numeric_limits<std::uint32_t>::max())
    throw InvalidArgument("Database: more than 4 GiB of postings in one segment");
  auto merged = std::make_unique<detail::Segment>();
  merged->first_entry = segments[begin]->first_entry;
  merged->end_entry = segments[end - 1]->end_entry;
  merged->level = segments[begin]->level + 1;
  merged->offsets.resize(segments[begin]->offsets.size());
  merged->bytes.resize(bytes);
  merged->posting_count = postings;
  // Nothing below can throw (shrinking never does; word weights are of
  // words in the vocabulary).
  merged->bytes.resize(merge_rows(segments.data() + begin, segments.data() + end, *merged,
                                  segment_weights(merged->first_entry)));
  for (std::size_t i = begin; i < end; ++i) merged->dead_postings += segments[i]->dead_postings;
  segments[begin] = std::move(merged);
  segments.erase(segments.begin() + static_cast<std::ptrdiff_t>(begin) + 1,
                 segments.begin() + static_cast<std::ptrdiff_t>(end));
}

std::unique_ptr<detail::Segment> Database::Impl::tail_as_segment() const {
  const std::size_t live = tail_postings - tail_dead_postings;
  if (live == 0) return nullptr;
  auto segment = std::make_unique<detail::Segment>();
  segment->offsets.resize(word_capacity + 1);
  segment->first_entry = tail_first_entry;
  segment->end_entry = static_cast<EntryId>(alive.size());
  segment->posting_count = live;
  // Room for every posting with a 2-byte gap and a header per row; shrunk to
  // what the rows take.
  segment->bytes.resize(live * (detail::kMaxGapWidth + detail::kWeightBytes) +
                        std::min(live, word_capacity) * detail::kRowHeaderBytes);
  std::uint8_t* const bytes = segment->bytes.data();
  std::uint32_t* const offsets = segment->offsets.data();
  const std::uint8_t* live_at = alive.data() + tail_first_entry;
  const double* divisor_at = divisors.data() + tail_first_entry;
  const float* vocabulary_weights = detail::word_weights(vocabulary);
  const bool drop_dead = tail_dead_postings > 0;
  const std::uint32_t row_mask = (1u << high_bits) - 1;
  // Per row of a list: its postings then next byte, its gaps ORed then gap
  // width, its last entry; whether every entry of the row is in count form
  // (a count row), then 1 / its word's vocabulary weight if so.
  const std::size_t list_rows = std::size_t{1} << high_bits;
  std::vector<std::uint32_t> next(list_rows), gaps(list_rows), last(list_rows);
  std::vector<std::uint8_t> counted(list_rows);
  std::vector<double> inverse_weights(list_rows);
  constexpr std::size_t kAhead = 2;
  constexpr std::size_t kLinesAhead = 4;
  std::uint32_t row_end = 0;
  // List by list, its consecutive rows: the first pass over the list's
  // postings sizes them (a gap's width depends on the row's previous entry),
  // the second writes them. Within a list entries increase, so the rows come
  // out in entry order.
  for (std::size_t l = 0; l < tail_lists.size(); ++l) {
    if (l + kAhead < tail_lists.size() && tail_lists[l + kAhead].size != 0) {
      const auto* ahead = reinterpret_cast<const char*>(arena.at(tail_lists[l + kAhead].block));
      for (std::size_t line = 0; line < kLinesAhead; ++line) __builtin_prefetch(ahead + 64 * line);
    }
    const auto list = static_cast<std::uint32_t>(l);
    const std::uint32_t first_row = tail_list_start(list);
    const std::uint32_t rows =
        (l + 1 < tail_lists.size() ? tail_list_start(list + 1)
                                   : static_cast<std::uint32_t>(word_capacity)) -
        first_row;
    const detail::TailPosting* postings =
        tail_lists[l].size != 0 ? arena.at(tail_lists[l].block) : nullptr;
    const std::uint32_t size = tail_lists[l].size;
    std::fill(next.begin(), next.begin() + rows, 0);
    std::fill(gaps.begin(), gaps.begin() + rows, 0);
    std::fill(counted.begin(), counted.begin() + rows, 1);
    std::fill(last.begin(), last.begin() + rows, detail::kRowStart);
    for (std::uint32_t i = 0; i < size; ++i) {
      const std::uint32_t key = postings[i].key;
      const std::uint32_t relative = key >> high_bits;
      if (drop_dead && live_at[relative] == 0) continue;
      const std::uint32_t row = key & row_mask;
      ++next[row];
      gaps[row] |= relative - last[row] - 1;
      counted[row] &= divisor_at[relative] > 0 ? 1 : 0;
      last[row] = relative;
    }
    // The list's rows are its groups' in order, a group's words increasing
    // (RowOrder).
    std::uint32_t r = 0;
    for (std::uint32_t g = list << tail_list_shift; r < rows; ++g) {
      for (std::size_t word = g; word < word_capacity;
           word += std::size_t{1} << detail::kGroupBits, ++r) {
        offsets[first_row + r] = row_end;
        if (next[r] == 0) continue;
        const std::uint32_t begin = row_end;
        row_end += static_cast<std::uint32_t>(detail::row_bytes(next[r], gaps[r], counted[r] != 0));
        gaps[r] = static_cast<std::uint32_t>(detail::gap_width(gaps[r]));
        bytes[begin] =
            static_cast<std::uint8_t>(gaps[r] | (counted[r] != 0 ? detail::kCountRow : 0));
        if (counted[r] != 0) inverse_weights[r] = 1 / static_cast<double>(vocabulary_weights[word]);
        next[r] = begin + static_cast<std::uint32_t>(detail::kRowHeaderBytes);
        last[r] = detail::kRowStart;
      }
    }
    for (std::uint32_t i = 0; i < size; ++i) {
      const std::uint32_t key = postings[i].key;
      const std::uint32_t relative = key >> high_bits;
      if (drop_dead && live_at[relative] == 0) continue;
      const std::uint32_t row = key & row_mask;
      std::uint8_t* const at = bytes + next[row];
      const std::uint32_t gap = relative - last[row] - 1;
      next[row] = static_cast<std::uint32_t>(
          (counted[row] != 0 ? detail::put_count_posting(
                                   at, gaps[row], gap,
                                   detail::count_of(postings[i].weight, inverse_weights[row],
                                                    divisor_at[relative]))
                             : detail::put_posting(at, gaps[row], gap, postings[i].weight)) -
          bytes);
      last[row] = relative;
    }
  }
  offsets[word_capacity] = row_end;
  segment->bytes.resize(row_end);  // shrinking never throws
  return segment;
}

void Database::Impl::freeze_tail() {
  std::unique_ptr<detail::Segment> segment = tail_as_segment();
  if (segment) segments.reserve(segments.size() + 1);
  // Nothing below can throw: the index changes all at once.
  if (segment) segments.push_back(std::move(segment));
  for (std::size_t list = 0; list < tail_lists.size(); ++list) {
    const std::uint32_t size = tail_lists[list].size;
    // At most 2^16 postings (512 KiB): a burst in one round does not
    // reserve much in the next.
    first_block_logs[list] = static_cast<std::uint8_t>(
        size <= (1u << detail::kFirstBlockLog) ? detail::kFirstBlockLog
                                               : std::min(32 - __builtin_clz(size - 1), 16));
    tail_lists[list] = {};
  }
  arena.reset();
  tail_postings = 0;
  tail_dead_postings = 0;
  tail_first_entry = static_cast<EntryId>(alive.size());
}

namespace {

// Writes the rows without the postings of removed entries into `out`
// (room for each kept posting with a 2-byte gap, and a header per row);
// returns the bytes written.
std::size_t drop_dead_postings(detail::Segment& segment, const std::uint8_t* live_at,
                               const detail::SegmentWeights& weights,
                               std::uint8_t* const out_begin) {
  std::uint32_t* offsets = segment.offsets.data();
  const std::uint8_t* const bytes = std::as_const(segment.bytes).data();
  std::uint8_t* out = out_begin;
  std::size_t kept = 0;
  std::uint32_t begin = offsets[0];
  detail::RowOrder::for_each_row(segment.offsets.size() - 1, [&](std::uint32_t w, WordId word) {
    const std::uint32_t end = offsets[w + 1];
    std::uint32_t last = detail::kRowStart;
    detail::RowWriter row(out, weights, word);
    detail::for_each_posting(bytes + begin, bytes + end,
                             [&](std::uint32_t entry, detail::PostingValue value) {
                               if (live_at[entry] == 0) return;
                               row.put(entry - last - 1, value);
                               last = entry;
                               ++kept;
                             });
    out = row.finish();
    offsets[w + 1] = static_cast<std::uint32_t>(out - out_begin);
    begin = end;
  });
  segment.posting_count = kept;
  return static_cast<std::size_t>(out - out_begin);
}

}  // namespace

void Database::Impl::compact(std::size_t index) {
  detail::Segment& segment = *segments[index];
  if (segment.dead_postings == segment.postings()) {
    segments.erase(segments.begin() + static_cast<std::ptrdiff_t>(index));
    return;
  }
  // A gap that absorbs dropped postings may widen its row: the rows go to
  // a new block. Without memory for it the segment stays as it is (queries
  // skip removed entries), so that remove never fails half done.
  const std::size_t live = segment.postings() - segment.dead_postings;
  detail::GrowableArray<std::uint8_t> kept;
  try {
    kept.resize(live * detail::kWriterSlotBytes + std::min(live, segment.offsets.size() - 1));
  } catch (const std::bad_alloc&) {
    return;
  }
  // Shrinking never throws (nor do word weights of the vocabulary's words).
  kept.resize(drop_dead_postings(segment, alive.data() + segment.first_entry,
                                 segment_weights(segment.first_entry), kept.data()));
  segment.bytes.swap(kept);
  segment.dead_postings = 0;
}

void Database::Impl::merge_file_check() {
  throw_if_damaged();
  if (file_check_merged) return;
  const detail::BackgroundCheck::Found& found = file_check->wait();
  // Entries added since load() have their counts already.
  std::copy(found.word_counts.begin(), found.word_counts.end(), word_counts.begin());
  values.negative = values.negative || found.values.negative;
  values.min_positive = std::min(values.min_positive, found.values.min_positive);
  values.max = std::max(values.max, found.values.max);
  file_check_merged = true;
}

bool Database::Impl::index_values(detail::ValueRange& range) const noexcept {
  range = values;
  if (file_check_merged) return true;
  if (!file_check->passed()) return false;
  const detail::ValueRange& found = file_check->found().values;
  range.negative = range.negative || found.negative;
  range.min_positive = std::min(range.min_positive, found.min_positive);
  range.max = std::max(range.max, found.max);
  return true;
}

std::size_t Database::Impl::segment_of(EntryId entry) const noexcept {
  if (entry >= tail_first_entry) return segments.size();
  const auto after = std::upper_bound(
      segments.begin(), segments.end(), entry,
      [](EntryId id, const std::unique_ptr<detail::Segment>& s) { return id < s->first_entry; });
  return static_cast<std::size_t>(after - segments.begin()) - 1;
}

}  // namespace binbow
