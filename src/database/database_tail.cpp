// The tail: where added entries go, one posting list per group of words,
// until it is frozen into a segment (database_segments.cpp).
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

namespace detail {

InvalidArgument non_finite_value(const char* what, WordId word) {
  return InvalidArgument(std::string(what) + ": word " + std::to_string(word) +
                         " has a non-finite value");
}

void check_bow_words(const BowVector& bow, const Vocabulary& vocabulary, const char* what) {
  if (!bow.empty() && bow[bow.size() - 1].word >= vocabulary.word_count())
    throw InvalidArgument(
        std::string(what) + ": word id " + std::to_string(bow[bow.size() - 1].word) +
        " is outside the vocabulary (" + std::to_string(vocabulary.word_count()) + " words)");
}

void check_bow_values(const BowVector& bow, const char* what) {
  for (const BowEntry& entry : bow)
    if (!std::isfinite(entry.value)) throw non_finite_value(what, entry.word);
}

namespace {

// Moves a full list to a block twice its size (see TailList).
__attribute__((noinline)) void grow(TailList& list, unsigned first_block_log, PostingArena& arena) {
  const std::uint32_t capacity = list.size == 0 ? 1u << first_block_log : list.size * 2;
  const std::uint32_t block = arena.allocate(capacity);
  if (list.size > 0) {
    std::memcpy(arena.at(block), arena.at(list.block), list.size * sizeof(TailPosting));
    arena.release(list.block, list.size);
  }
  list.block = block;
}

// The range of a vector's values; false if one is not finite. Branch-free,
// so that the compiler may check several values at once.
bool finite_value_range(const BowEntry* words, std::size_t n, ValueRange& range) noexcept {
  // Four of each, so that the comparisons need not wait for one another.
  constexpr std::size_t kWays = 4;
  float min_positive[kWays], max[kWays], lowest[kWays];
  bool finite = true;
  std::fill(min_positive, min_positive + kWays, INFINITY);
  std::fill(max, max + kWays, 0.0f);
  std::fill(lowest, lowest + kWays, 0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    const float v = words[i].value;
    const std::size_t k = i % kWays;
    finite &= std::fabs(v) <= std::numeric_limits<float>::max();
    min_positive[k] = std::min(min_positive[k], v > 0.0f ? v : INFINITY);
    max[k] = std::max(max[k], v);
    lowest[k] = std::min(lowest[k], v);
  }
  for (std::size_t k = 1; k < kWays; ++k) {
    min_positive[0] = std::min(min_positive[0], min_positive[k]);
    max[0] = std::max(max[0], max[k]);
    lowest[0] = std::min(lowest[0], lowest[k]);
  }
  range.min_positive = min_positive[0];
  range.max = max[0];
  range.negative = lowest[0] < 0.0f;
  return finite;
}

}  // namespace

}  // namespace detail

namespace {

// The bits of the word ids below `capacity`.
unsigned word_bits(std::size_t capacity) noexcept {
  unsigned bits = 0;
  while (((capacity - 1) >> bits) != 0) ++bits;
  return bits;
}

// log2 of the groups per tail list for word ids below `capacity`:
// kTailListShift, or less where a key (the entry, then the word's row
// among its list's) needs it.
unsigned tail_list_shift_for(std::size_t capacity) noexcept {
  const unsigned bits = word_bits(capacity);
  const unsigned group_row_bits = bits > detail::kGroupBits ? bits - detail::kGroupBits : 0;
  return std::min(detail::kTailListShift, 32 - detail::kTailEntryBits - group_row_bits);
}

std::size_t tail_list_count(std::size_t capacity) noexcept {
  const std::size_t groups = std::min(capacity, std::size_t{1} << detail::kGroupBits);
  const unsigned shift = tail_list_shift_for(capacity);
  return (groups + (std::size_t{1} << shift) - 1) >> shift;
}

}  // namespace

void Database::Impl::lay_out(std::size_t capacity) {
  tail_lists.assign(tail_list_count(capacity), {});
  first_block_logs.assign(tail_lists.size(), detail::kFirstBlockLog);
  set_word_capacity(capacity);
}

void Database::Impl::set_word_capacity(std::size_t capacity) noexcept {
  word_capacity = capacity;
  tail_list_shift = tail_list_shift_for(capacity);
  const unsigned bits = word_bits(capacity);
  high_bits = (bits > detail::kGroupBits ? bits - detail::kGroupBits : 0) + tail_list_shift;
  row_order = detail::RowOrder(word_capacity);
  // Two postings per word: a segment's offsets (4 bytes per word) cost 2
  // bytes per posting; two thousand images of 1000 words for a million
  // words. Within bounds, so that small vocabularies make segments of
  // useful size and a huge one does not grow the tail that queries scan.
  segment_postings = std::clamp(2 * word_capacity, std::size_t{1} << 16, std::size_t{1} << 22);
}

namespace {

// A segment's rows (RowOrder of `old_words`) re-laid for `new_words` ≥
// old_words into `new_bytes`: the words keep their postings, the new words
// get empty rows. Returns the new offsets.
std::vector<std::uint32_t> relay_rows(const detail::Segment& segment, std::uint8_t* new_bytes,
                                      std::size_t old_words, std::size_t new_words) {
  const detail::RowOrder old_order(old_words);
  std::vector<std::uint32_t> offsets(new_words + 1);
  std::uint32_t at = 0;
  std::size_t row = 0;
  offsets[0] = 0;
  constexpr std::size_t kGroups = std::size_t{1} << detail::kGroupBits;
  for (std::size_t group = 0; group < std::min(new_words, kGroups); ++group) {
    for (std::size_t word = group; word < new_words; word += kGroups) {
      if (word < old_words) {
        const std::uint32_t old_row = old_order.row(static_cast<WordId>(word));
        const std::uint32_t from = segment.offsets[old_row];
        const std::uint32_t bytes = segment.offsets[old_row + 1] - from;
        if (bytes > 0) std::memcpy(new_bytes + at, segment.bytes.data() + from, bytes);
        at += bytes;
      }
      offsets[++row] = at;
    }
  }
  return offsets;
}

// One segment's arrays for the new capacity, built before any is replaced.
struct RelaidSegment {
  std::vector<std::uint32_t> offsets;
  detail::GrowableArray<std::uint8_t> bytes;
};

}  // namespace

void Database::Impl::grow_words(std::size_t needed) {
  if (needed <= word_capacity) return;
  constexpr std::size_t kWordIds = std::size_t{1} << 32;
  if (needed > kWordIds)
    throw InvalidArgument("Database: word id " + std::to_string(needed - 1) + " is too large");
  const std::size_t new_words = std::min(std::max(needed, 2 * word_capacity), kWordIds);
  // The tail's keys and lists depend on the capacity: make it a segment first.
  freeze_tail();
  // Everything is allocated before anything changes, so that running out of
  // memory leaves the index as it was (with its tail frozen).
  std::vector<RelaidSegment> relaid(segments.size());
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const detail::Segment& segment = *segments[i];
    RelaidSegment& out = relaid[i];
    out.bytes.resize(segment.bytes.size());
    out.offsets = relay_rows(segment, out.bytes.data(), word_capacity, new_words);
  }
  std::vector<detail::TailList> lists(tail_list_count(new_words));
  std::vector<std::uint8_t> block_logs(lists.size(), detail::kFirstBlockLog);
  for (std::size_t i = 0; i < segments.size(); ++i) {
    detail::Segment& segment = *segments[i];
    segment.offsets.swap(relaid[i].offsets);
    segment.bytes.swap(relaid[i].bytes);
  }
  tail_lists.swap(lists);
  first_block_logs.swap(block_logs);
  set_word_capacity(new_words);
}

EntryId Database::Impl::append(const BowVector& bow, const FeatureVector& features) {
  if (alive.size() >= kAllEntries)
    throw InvalidArgument("Database: no entry id left (" + std::to_string(alive.size()) +
                          " entries added)");
  const auto entry = static_cast<EntryId>(alive.size());
  // Tail entries are 16-bit offsets. freeze_tail_if_full keeps the tail
  // within kSegmentSpan entries unless it ran out of memory: then try again,
  // and if that fails too, this add fails with nothing changed.
  if (entry - tail_first_entry >= detail::kSegmentSpan) freeze_tail();
  const BowEntry* words = bow.begin();
  const std::size_t n = bow.size();
  detail::ValueRange range;
  if (!detail::finite_value_range(words, n, range))
    for (std::size_t i = 0; i < n; ++i)
      if (!std::isfinite(words[i].value))
        throw detail::non_finite_value("Database::add", words[i].word);
  const std::uint32_t key_base = (entry - tail_first_entry) << high_bits;
  std::size_t appended = 0;
  try {
    alive.push_back(0);
    word_counts.push_back(static_cast<std::uint32_t>(n));
    // The lists' heads and the ends of their blocks mostly stay in cache
    // (see kTailListShift), but one store in eight starts a cache line: the
    // line a later word writes is fetched kAhead words ahead, so that those
    // misses overlap, and so is the word's vocabulary weight, which the count
    // form reads next, in word order, one cache miss per word otherwise.
    constexpr std::size_t kAhead = 16;
    const float* const weights_ahead = over_word_ids ? nullptr : detail::word_weights(vocabulary);
    detail::TailList* lists = tail_lists.data();
    for (; appended < n; ++appended) {
      if (appended + kAhead < n) {
        const WordId ahead = words[appended + kAhead].word;
        const detail::TailList next = lists[tail_list(ahead)];
        if (next.size != 0) __builtin_prefetch(arena.at(next.block) + next.size, 1);
        if (weights_ahead != nullptr) __builtin_prefetch(weights_ahead + ahead);
      }
      const WordId word = words[appended].word;
      const std::uint32_t l = tail_list(word);
      detail::TailList& list = lists[l];
      if (detail::tail_list_full(list.size, first_block_logs[l]))
        detail::grow(list, first_block_logs[l], arena);
      arena.at(list.block)[list.size++] = {key_base | (row_order.row(word) - tail_list_start(l)),
                                           words[appended].value};
    }
    // The count form, found once: the divisor the count rows use, and the
    // forward index's compact entry.
    const bool counted =
        !over_word_ids && count_form.find(vocabulary, scoring, Span<BowEntry>(words, n));
    divisors.push_back(
        counted && count_form.largest_count() <= detail::kMaxRowCount ? count_form.divisor() : 0);
    if (options.direct_index) direct.emplace_back(features);
    if (!labels.empty()) labels.emplace_back();
    if (forward_built) forward.append(Span<BowEntry>(words, n), counted ? &count_form : nullptr);
  } catch (...) {
    // The lists that got this entry end with it; undo them.
    for (std::size_t i = 0; i < appended; ++i) --tail_lists[tail_list(words[i].word)].size;
    alive.resize(entry);
    word_counts.resize(entry);
    divisors.resize(entry);
    if (direct.size() > entry) direct.resize(entry);
    if (labels.size() > entry) labels.resize(entry);
    if (forward_built) forward.truncate(entry);
    throw;
  }
  values.include(range);
  alive[entry] = 1;
  ++live_entries;
  tail_postings += n;
  return entry;
}

void Database::Impl::build_forward_index() const {
  if (forward_built.load(std::memory_order_acquire)) return;
  std::lock_guard<std::mutex> lock(forward_mutex);
  if (forward_built.load(std::memory_order_relaxed)) return;
  wait_for_file();  // reads every posting: only checked ones
  detail::ForwardIndex built(over_word_ids ? nullptr : &vocabulary, scoring);
  built.resize(alive.size());
  // The words of kChunk entries at a time, so that the BoW vectors in
  // floats never exist all at once: each segment's rows are read chunk by
  // chunk (entries are increasing within a row), the tail's lists likewise.
  constexpr EntryId kChunk = 4096;
  std::vector<std::vector<BowEntry>> words(kChunk);
  const auto encode_chunk = [&](EntryId first, EntryId end) {
    for (EntryId entry = first; entry < end; ++entry) {
      std::vector<BowEntry>& entry_words = words[entry - first];
      if (alive[entry] != 0)
        built.assign(entry, Span<BowEntry>(entry_words.data(), entry_words.size()));
      entry_words.clear();
    }
  };
  std::vector<std::uint32_t> cursors, last_entries;
  for (const auto& segment : segments) {
    const std::uint32_t* offsets = segment->offsets.data();
    const std::uint8_t* bytes = std::as_const(segment->bytes).data();
    // By row: the next posting's byte, past the row's header.
    cursors.resize(word_capacity);
    for (std::size_t row = 0; row < word_capacity; ++row)
      cursors[row] = offsets[row] + (offsets[row] != offsets[row + 1] ? 1 : 0);
    last_entries.assign(word_capacity, detail::kRowStart);
    for (EntryId first = segment->first_entry; first < segment->end_entry; first += kChunk) {
      const EntryId end = std::min<EntryId>(first + kChunk, segment->end_entry);
      const auto relative_end = static_cast<std::uint32_t>(end - segment->first_entry);
      for (std::size_t word = 0; word < word_capacity; ++word) {
        const std::uint32_t row = row_order.row(static_cast<WordId>(word));
        std::uint32_t& i = cursors[row];
        std::uint32_t& last = last_entries[row];
        if (i >= offsets[row + 1]) continue;
        const std::uint8_t header = bytes[offsets[row]];
        const std::size_t width = detail::header_width(header);
        const std::size_t stride = detail::header_stride(header);
        const detail::RowWeights weights =
            detail::header_counts(header)
                ? segment_weights(segment->first_entry).row(static_cast<WordId>(word))
                : detail::RowWeights{};
        for (; i < offsets[row + 1]; i += static_cast<std::uint32_t>(stride)) {
          const std::uint8_t* at = bytes + i;
          const std::uint32_t relative = last + detail::read_gap(at, width) + 1;
          if (relative >= relative_end) break;
          const float weight = detail::header_counts(header) ? weights.weight(relative, at[width])
                                                             : detail::read_weight(at + width);
          words[segment->first_entry + relative - first].push_back(
              {static_cast<WordId>(word), weight});
          last = relative;
        }
      }
      encode_chunk(first, end);
    }
  }
  const std::uint32_t high_mask = (1u << high_bits) - 1;
  cursors.assign(tail_lists.size(), 0);
  for (EntryId first = tail_first_entry; first < alive.size() && tail_postings > 0;
       first += kChunk) {
    const EntryId end = static_cast<EntryId>(std::min<std::size_t>(first + kChunk, alive.size()));
    const std::uint64_t key_end = std::uint64_t{end - tail_first_entry} << high_bits;
    for (std::size_t word = 0; word < word_capacity; ++word) {
      const std::uint32_t group = tail_list(static_cast<WordId>(word));
      const detail::TailList list = tail_lists[group];
      if (list.size == 0) continue;
      const detail::TailPosting* postings = arena.at(list.block);
      const std::uint32_t high = tail_row(static_cast<WordId>(word));
      for (std::uint32_t i = cursors[group]; i < list.size && postings[i].key < key_end; ++i)
        if ((postings[i].key & high_mask) == high)
          words[tail_first_entry + (postings[i].key >> high_bits) - first].push_back(
              {static_cast<WordId>(word), postings[i].weight});
    }
    for (std::size_t group = 0; group < tail_lists.size(); ++group) {
      const detail::TailList list = tail_lists[group];
      if (list.size == 0) continue;
      const detail::TailPosting* postings = arena.at(list.block);
      std::uint32_t& i = cursors[group];
      while (i < list.size && postings[i].key < key_end) ++i;
    }
    encode_chunk(first, end);
  }
  forward = std::move(built);
  forward_built.store(true, std::memory_order_release);
}

}  // namespace binbow
