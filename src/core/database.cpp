// The image database: posting lists, packed direct index, queries through the
// inverted index. The .bbdb format lives in database_file.cpp.
#include "binbow/database.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>
#include <new>
#include <utility>

#include "binbow/error.h"
#include "core/database_impl.h"
#include "core/scoring.h"

namespace binbow {

namespace detail {

std::uint32_t PostingArena::new_chunk(std::size_t postings) {
  // Addresses are 32 bits: chunk index, then kChunkBits of position.
  if (chunks_.size() >= (std::size_t{1} << (32 - kChunkBits)))
    throw InvalidArgument("Database: the tail tier outgrew its 32 GiB of addresses");
  chunk_starts_.reserve(chunks_.size() + 1);
  chunk_postings_.reserve(chunks_.size() + 1);
  chunks_.emplace_back(new TailPosting[postings]);  // left uninitialised
  chunk_starts_.push_back(chunks_.back().get());
  chunk_postings_.push_back(postings);
  chunk_bytes_ += postings * sizeof(TailPosting);
  return static_cast<std::uint32_t>((chunks_.size() - 1) << kChunkBits);
}

std::uint32_t PostingArena::allocate(std::uint32_t capacity) {
  const auto size_class = static_cast<unsigned>(__builtin_ctz(capacity));
  const std::uint32_t reused = free_lists_[size_class];
  if (reused != kNoBlock) {
    std::memcpy(&free_lists_[size_class], at(reused), sizeof(std::uint32_t));
    // The next allocation of this size reads that block: fetch it now.
    if (free_lists_[size_class] != kNoBlock) __builtin_prefetch(at(free_lists_[size_class]));
    return reused;
  }
  constexpr std::uint32_t kChunkPostings = std::uint32_t{1} << kChunkBits;
  if (capacity > kChunkPostings) return new_chunk(capacity);  // a chunk of its own
  if (bump_left_ < capacity) {
    bump_ = spare_begin_ < spare_end_ ? static_cast<std::uint32_t>(spare_begin_++ << kChunkBits)
                                      : new_chunk(kChunkPostings);
    bump_left_ = kChunkPostings;
  }
  const std::uint32_t block = bump_;
  bump_ += capacity;
  bump_left_ -= capacity;
  return block;
}

void PostingArena::release(std::uint32_t block, std::uint32_t capacity) noexcept {
  const auto size_class = static_cast<unsigned>(__builtin_ctz(capacity));
  std::memcpy(at(block), &free_lists_[size_class], sizeof(std::uint32_t));
  free_lists_[size_class] = block;
}

void PostingArena::reset() noexcept {
  // Blocks larger than a chunk have chunks of their own: those go.
  constexpr std::size_t kChunkPostings = std::size_t{1} << kChunkBits;
  std::size_t kept = 0;
  for (std::size_t c = 0; c < chunks_.size(); ++c) {
    if (chunk_postings_[c] != kChunkPostings) continue;
    chunks_[kept] = std::move(chunks_[c]);
    chunk_starts_[kept] = chunk_starts_[c];
    chunk_postings_[kept] = kChunkPostings;
    ++kept;
  }
  chunks_.resize(kept);
  chunk_starts_.resize(kept);
  chunk_postings_.resize(kept);
  chunk_bytes_ = kept * kChunkPostings * sizeof(TailPosting);
  std::fill(std::begin(free_lists_), std::end(free_lists_), kNoBlock);
  bump_ = 0;
  bump_left_ = 0;
  spare_begin_ = 0;
  spare_end_ = kept;
}

void PostingArena::clear() noexcept {
  chunks_.clear();
  chunk_starts_.clear();
  chunk_postings_.clear();
  std::fill(std::begin(free_lists_), std::end(free_lists_), kNoBlock);
  bump_ = 0;
  bump_left_ = 0;
  spare_begin_ = 0;
  spare_end_ = 0;
  chunk_bytes_ = 0;
}

namespace {

bool is_power_of_two_or_zero(std::uint32_t n) noexcept {
  return (n & (n - 1)) == 0;
}

// A list whose size is 0 or a power of two is full (see TailList).
void push_back(TailList& list, TailPosting posting, PostingArena& arena) {
  if (is_power_of_two_or_zero(list.size)) {
    const std::uint32_t capacity = list.size == 0 ? 1 : list.size * 2;
    const std::uint32_t block = arena.allocate(capacity);
    if (list.size > 0) {
      const TailPosting* from = arena.at(list.block);
      TailPosting* to = arena.at(block);
      for (std::uint32_t i = 0; i < list.size; ++i) to[i] = from[i];
      arena.release(list.block, list.size);
    }
    list.block = block;
  }
  arena.at(list.block)[list.size++] = posting;
}

}  // namespace

PackedFeatureVector::PackedFeatureVector(const FeatureVector& features)
    : node_count_(static_cast<std::uint32_t>(features.size())),
      feature_count_(static_cast<std::uint32_t>(features.feature_count())) {
  const auto& indices = features.feature_indices();
  bool partition = node_count_ <= 0x10000;
  if (partition) {
    std::vector<bool> seen(feature_count_, false);
    for (std::uint32_t index : indices) {
      if (index >= feature_count_ || seen[index]) {
        partition = false;
        break;
      }
      seen[index] = true;
    }
  }
  const bool wide =
      feature_count_ > 0xFFFF ||
      std::any_of(indices.begin(), indices.end(), [](std::uint32_t i) { return i > 0xFFFF; });
  if (partition)
    layout_ = node_count_ <= 0x100 ? Layout::kPartition8 : Layout::kPartition16;
  else
    layout_ = wide ? Layout::kRows32 : Layout::kRows16;
  const std::size_t nodes_bytes = std::size_t{node_count_} * 4;
  if (partition) {
    const std::size_t width = layout_ == Layout::kPartition8 ? 1 : 2;
    bytes_.resize(nodes_bytes + std::size_t{feature_count_} * width);
    if (node_count_ > 0) std::memcpy(bytes_.data(), features.nodes().data(), nodes_bytes);
    std::uint8_t* slots = bytes_.data() + nodes_bytes;
    for (std::size_t node = 0; node < node_count_; ++node) {
      for (std::uint32_t index : features.features(node)) {
        const auto slot = static_cast<std::uint16_t>(node);
        std::memcpy(slots + std::size_t{index} * width, &slot, width);  // little-endian
      }
    }
    return;
  }
  const std::size_t width = layout_ == Layout::kRows32 ? 4 : 2;
  bytes_.resize(nodes_bytes + std::size_t{node_count_} * width +
                std::size_t{feature_count_} * width);
  std::uint8_t* out = bytes_.data();
  if (node_count_ > 0) std::memcpy(out, features.nodes().data(), nodes_bytes);
  out += nodes_bytes;
  const auto put = [&](std::uint32_t v) {
    std::memcpy(out, &v, width);  // little-endian: the low bytes
    out += width;
  };
  for (std::size_t i = 1; i <= node_count_; ++i) put(features.offsets()[i]);
  for (std::uint32_t index : indices) put(index);
}

std::uint32_t PackedFeatureVector::value(std::size_t byte_offset,
                                         std::size_t width) const noexcept {
  std::uint32_t v = 0;
  std::memcpy(&v, bytes_.data() + byte_offset, width);  // little-endian
  return v;
}

FeatureVector PackedFeatureVector::unpack() const {
  std::vector<NodeId> nodes(node_count_);
  const std::size_t nodes_bytes = std::size_t{node_count_} * 4;
  if (node_count_ > 0) std::memcpy(nodes.data(), bytes_.data(), nodes_bytes);
  std::vector<std::uint32_t> offsets(std::size_t{node_count_} + 1, 0);
  std::vector<std::uint32_t> indices(feature_count_);
  if (layout_ == Layout::kPartition8 || layout_ == Layout::kPartition16) {
    // Counting sort of the features by node; increasing index within a node.
    const std::size_t width = layout_ == Layout::kPartition8 ? 1 : 2;
    for (std::size_t f = 0; f < feature_count_; ++f)
      ++offsets[value(nodes_bytes + f * width, width) + 1];
    for (std::size_t i = 0; i < node_count_; ++i) offsets[i + 1] += offsets[i];
    std::vector<std::uint32_t> next(offsets.begin(), offsets.end() - 1);
    for (std::uint32_t f = 0; f < feature_count_; ++f)
      indices[next[value(nodes_bytes + f * width, width)]++] = f;
  } else {
    const std::size_t width = layout_ == Layout::kRows32 ? 4 : 2;
    std::size_t at = nodes_bytes;
    for (std::size_t i = 1; i <= node_count_; ++i, at += width) offsets[i] = value(at, width);
    for (auto& index : indices) {
      index = value(at, width);
      at += width;
    }
  }
  return FeatureVector::from_arrays(std::move(nodes), std::move(offsets), std::move(indices));
}

}  // namespace detail

namespace {

struct Accumulator {
  double sum = 0;
  std::uint32_t shared = 0;
};

// Per-thread buffers reused by every query: the dense score array (all zero
// between queries), the ids touched by the current query, the candidates.
struct QueryScratch {
  std::vector<Accumulator> accumulators;
  std::vector<EntryId> touched;
  std::vector<QueryResult> candidates;
};

thread_local QueryScratch scratch;

struct IndexView {
  const std::uint32_t* main_offsets;  // null when the main tier is empty
  const EntryId* main_ids;
  const float* main_weights;
  const detail::TailList* tail_lists;
  const detail::PostingArena* arena;
};

template <Scoring kScoring>
inline void accumulate_posting(EntryId entry, float weight, double v, Accumulator* accumulators,
                               EntryId* touched, std::size_t& touched_count) {
  Accumulator& accumulator = accumulators[entry];
  touched[touched_count] = entry;
  touched_count += accumulator.shared == 0;
  ++accumulator.shared;
  accumulator.sum += detail::score_term(kScoring, v, weight);
}

// Adds the terms of one word's postings; ids increase, so `last_entry` cuts
// them short.
template <Scoring kScoring>
inline void accumulate_main(const EntryId* ids, const float* weights, std::uint32_t count, double v,
                            EntryId last_entry, Accumulator* accumulators, EntryId* touched,
                            std::size_t& touched_count) {
  if (count > 0 && ids[count - 1] > last_entry)
    count = static_cast<std::uint32_t>(std::upper_bound(ids, ids + count, last_entry) - ids);
  for (std::uint32_t i = 0; i < count; ++i)
    accumulate_posting<kScoring>(ids[i], weights[i], v, accumulators, touched, touched_count);
}

template <Scoring kScoring>
inline void accumulate_tail(const detail::TailPosting* postings, std::uint32_t count, double v,
                            EntryId last_entry, Accumulator* accumulators, EntryId* touched,
                            std::size_t& touched_count) {
  if (count > 0 && postings[count - 1].entry > last_entry)
    count = static_cast<std::uint32_t>(
        std::upper_bound(postings, postings + count, last_entry,
                         [](EntryId id, const detail::TailPosting& p) { return id < p.entry; }) -
        postings);
  for (std::uint32_t i = 0; i < count; ++i)
    accumulate_posting<kScoring>(postings[i].entry, postings[i].weight, v, accumulators, touched,
                                 touched_count);
}

// Every term is computed and summed exactly as Vocabulary::score does, in the
// same order (increasing word id), so scores agree to the last bit. Posting
// lists are scattered in memory: the lists of words a few steps ahead are
// prefetched so that their cache misses overlap.
template <Scoring kScoring>
std::size_t accumulate(IndexView index, const BowVector& bow, EntryId last_entry,
                       Accumulator* accumulators, EntryId* touched) {
  constexpr std::size_t kAhead = 8;
  std::size_t touched_count = 0;
  const std::size_t n = bow.size();
  const BowEntry* query = bow.begin();
  for (std::size_t q = 0; q < n; ++q) {
    if (q + 2 * kAhead < n) {
      const WordId far = query[q + 2 * kAhead].word;
      if (index.main_offsets != nullptr) __builtin_prefetch(index.main_offsets + far);
      __builtin_prefetch(index.tail_lists + far);
    }
    if (q + kAhead < n) {
      const WordId near = query[q + kAhead].word;
      if (index.main_offsets != nullptr) {
        const std::uint32_t begin = index.main_offsets[near];
        __builtin_prefetch(index.main_ids + begin);
        __builtin_prefetch(index.main_weights + begin);
      }
      const detail::TailList list = index.tail_lists[near];
      if (list.size != 0) __builtin_prefetch(index.arena->at(list.block));
    }
    const WordId word = query[q].word;
    const double v = query[q].value;
    if (index.main_offsets != nullptr) {
      const std::uint32_t begin = index.main_offsets[word];
      accumulate_main<kScoring>(index.main_ids + begin, index.main_weights + begin,
                                index.main_offsets[word + 1] - begin, v, last_entry, accumulators,
                                touched, touched_count);
    }
    const detail::TailList list = index.tail_lists[word];
    if (list.size != 0)
      accumulate_tail<kScoring>(index.arena->at(list.block), list.size, v, last_entry, accumulators,
                                touched, touched_count);
  }
  return touched_count;
}

std::size_t accumulate(Scoring scoring, IndexView impl, const BowVector& bow, EntryId last_entry,
                       Accumulator* accumulators, EntryId* touched) {
  switch (scoring) {
    case Scoring::kL1:
      return accumulate<Scoring::kL1>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kL2:
      return accumulate<Scoring::kL2>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kChiSquare:
      return accumulate<Scoring::kChiSquare>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kKL:
      return accumulate<Scoring::kKL>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kBhattacharyya:
      return accumulate<Scoring::kBhattacharyya>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kDotProduct:
      return accumulate<Scoring::kDotProduct>(impl, bow, last_entry, accumulators, touched);
  }
  return 0;
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

void check_bow(const BowVector& bow, const Vocabulary& vocabulary, const char* what) {
  if (!bow.empty() && bow[bow.size() - 1].word >= vocabulary.word_count())
    throw InvalidArgument(
        std::string(what) + ": word id " + std::to_string(bow[bow.size() - 1].word) +
        " is outside the vocabulary (" + std::to_string(vocabulary.word_count()) + " words)");
  for (const BowEntry& entry : bow)
    if (!std::isfinite(entry.value))
      throw InvalidArgument(std::string(what) + ": word " + std::to_string(entry.word) +
                            " has a non-finite value");
}

std::string no_entry_message(EntryId entry, EntryId next) {
  if (entry >= next)
    return "entry " + std::to_string(entry) + " does not exist (the database has ids below " +
           std::to_string(next) + ")";
  return "entry " + std::to_string(entry) + " was removed";
}

// Walks the set bits of a bitmap from the highest to the lowest.
class TailWordCursor {
 public:
  static constexpr std::size_t kEnd = ~std::size_t{0};

  explicit TailWordCursor(const std::vector<std::uint64_t>& bits) noexcept
      : bits_(bits.data()), block_(bits.size()) {}

  std::size_t next() noexcept {
    while (current_ == 0) {
      if (block_ == 0) return kEnd;
      current_ = bits_[--block_];
    }
    const auto bit = static_cast<std::size_t>(63 - __builtin_clzll(current_));
    current_ &= ~(std::uint64_t{1} << bit);
    return block_ * 64 + bit;
  }

 private:
  const std::uint64_t* bits_;
  std::size_t block_;
  std::uint64_t current_ = 0;
};

}  // namespace

Database::Impl::Impl(Vocabulary vocabulary_in, DatabaseOptions options_in)
    : vocabulary(std::move(vocabulary_in)), options(options_in) {
  if (vocabulary.empty()) throw InvalidArgument("Database: the vocabulary is empty");
  tail_lists.resize(vocabulary.word_count());
  tail_words.resize((vocabulary.word_count() + 63) / 64);
}

EntryId Database::Impl::append(const BowVector& bow, const FeatureVector& features) {
  if (alive.size() >= kAllEntries)
    throw InvalidArgument("Database: no entry id left (" + std::to_string(alive.size()) +
                          " entries added)");
  const auto entry = static_cast<EntryId>(alive.size());
  const BowEntry* words = bow.begin();
  const std::size_t n = bow.size();
  std::size_t appended = 0;
  try {
    alive.push_back(0);
    word_counts.push_back(static_cast<std::uint32_t>(n));
    if (options.direct_index) direct.emplace_back(features);
    if (!labels.empty()) labels.emplace_back();
    // Each posting touches two cache lines nothing predicts: its word's list
    // and the end of that list's block. A software pipeline fetches the list
    // kListAhead words ahead and the block end kBlockAhead words ahead, so
    // their misses overlap instead of stalling the loop one after the other.
    constexpr std::size_t kListAhead = 24;
    constexpr std::size_t kBlockAhead = 12;
    detail::TailList* lists = tail_lists.data();
    for (; appended < n; ++appended) {
      if (appended + kListAhead < n) __builtin_prefetch(lists + words[appended + kListAhead].word);
      if (appended + kBlockAhead < n) {
        const detail::TailList ahead = lists[words[appended + kBlockAhead].word];
        if (ahead.size != 0) __builtin_prefetch(arena.at(ahead.block) + ahead.size);
      }
      const WordId word = words[appended].word;
      if (lists[word].size == 0) tail_words[word / 64] |= std::uint64_t{1} << (word % 64);
      detail::push_back(lists[word], {entry, words[appended].value}, arena);
    }
  } catch (...) {
    // The lists that got this entry end with it; undo them.
    for (std::size_t i = 0; i < appended; ++i)
      if (--tail_lists[words[i].word].size == 0)
        tail_words[words[i].word / 64] &= ~(std::uint64_t{1} << (words[i].word % 64));
    alive.resize(entry);
    word_counts.resize(entry);
    if (direct.size() > entry) direct.resize(entry);
    if (labels.size() > entry) labels.resize(entry);
    throw;
  }
  alive[entry] = 1;
  ++live_entries;
  postings += n;
  tail_postings += n;
  return entry;
}

void Database::Impl::merge_if_worthwhile() {
  constexpr std::size_t kMinimumTail = 1 << 16;
  if (tail_postings <= std::max(kMinimumTail, postings / 4) && dead_postings * 3 <= postings)
    return;
  try {
    merge();
  } catch (...) {
    // Out of memory for the merged copy: the two tiers stay valid as they
    // are, and the add or remove that got here has succeeded.
  }
}

// In place: the main arrays grow (realloc) to the merged size, then one pass
// from the last word with tail postings to the first moves the main runs
// right by the number of tail postings of the words before them and puts
// each word's tail postings after its main run. A word's new place never
// starts before its old one, so nothing is overwritten before it is read.
// The runs between two words with tail postings move together, so a merge
// costs the postings it moves plus one add per offset, and the tail blocks,
// the only scattered reads, are prefetched a few words ahead.
void Database::Impl::merge() {
  const std::size_t words = tail_lists.size();
  const std::size_t main_size = postings - tail_postings;
  std::size_t live_tail = tail_postings;
  std::size_t live_main = main_size;
  if (dead_postings > 0) {
    live_tail = 0;
    for (std::size_t entry = tail_first_entry; entry < alive.size(); ++entry)
      live_tail += alive[entry] != 0 ? word_counts[entry] : 0;
    live_main = postings - dead_postings - live_tail;
  }
  const std::size_t merged = live_main + live_tail;
  if (merged > std::numeric_limits<std::uint32_t>::max())
    throw InvalidArgument("Database: more than 2^32 postings");
  const bool first = main_offsets.empty();
  if (first) main_offsets.assign(words + 1, 0);
  try {
    if (merged > main_size) {
      main_ids.resize(merged);
      main_weights.resize(merged);
    }
  } catch (...) {
    if (first) std::vector<std::uint32_t>().swap(main_offsets);
    throw;
  }
  // Nothing below can throw: the index changes all at once.
  std::uint32_t* offsets = main_offsets.data();
  EntryId* ids = main_ids.data();
  float* weights = main_weights.data();
  if (live_main < main_size) {
    // Drop the main tier's dead postings first (moving left), so that the
    // pass below only ever moves postings right.
    std::uint32_t kept = 0;
    std::uint32_t begin = 0;
    for (std::size_t w = 0; w < words; ++w) {
      const std::uint32_t end = offsets[w + 1];
      for (std::uint32_t i = begin; i < end; ++i) {
        ids[kept] = ids[i];
        weights[kept] = weights[i];
        kept += alive[ids[i]];
      }
      begin = end;
      offsets[w + 1] = kept;
    }
  }

  const bool drop_dead = live_tail < tail_postings;
  const auto move_right = [&](std::uint32_t begin, std::uint32_t end, std::uint32_t shift) {
    if (shift == 0) return;
    if (end - begin > 64) {
      std::memmove(ids + begin + shift, ids + begin, std::size_t{end - begin} * sizeof(EntryId));
      std::memmove(weights + begin + shift, weights + begin,
                   std::size_t{end - begin} * sizeof(float));
      return;
    }
    for (std::uint32_t i = end; i-- > begin;) {  // most runs are short: no call
      ids[i + shift] = ids[i];
      weights[i + shift] = weights[i];
    }
  };
  // The words with tail postings, last first; the cursors ahead of the one
  // merging prefetch the list, then the block, of the words it comes to next.
  TailWordCursor far(tail_words), near(tail_words), current(tail_words);
  constexpr int kFar = 32;
  constexpr int kNear = 16;
  for (int i = 0; i < kFar; ++i) {
    const std::size_t w = far.next();
    if (w != TailWordCursor::kEnd) __builtin_prefetch(tail_lists.data() + w);
    if (i >= kFar - kNear) near.next();
  }
  std::size_t remaining = live_tail;  // of the words up to the current one
  std::size_t span_end = words;       // the first word already merged
  for (std::size_t w = current.next(); w != TailWordCursor::kEnd; w = current.next()) {
    const std::size_t w_far = far.next();
    if (w_far != TailWordCursor::kEnd) __builtin_prefetch(tail_lists.data() + w_far);
    const std::size_t w_near = near.next();
    if (w_near != TailWordCursor::kEnd) __builtin_prefetch(arena.at(tail_lists[w_near].block));
    // The words between this one and the last merged one have no tail
    // postings: their runs move right together.
    const auto shift = static_cast<std::uint32_t>(remaining);
    const std::uint32_t old_end = offsets[w + 1];
    move_right(old_end, offsets[span_end], shift);
    if (shift != 0)
      for (std::size_t u = w + 1; u <= span_end; ++u) offsets[u] += shift;
    // This word's tail postings go after its main run, which then moves
    // right by the tail postings of the words before it.
    detail::TailList& list = tail_lists[w];
    const detail::TailPosting* tail = arena.at(list.block);
    std::uint32_t to = old_end + shift;
    for (std::uint32_t i = list.size; i-- > 0;) {
      if (drop_dead && alive[tail[i].entry] == 0) continue;
      --to;
      ids[to] = tail[i].entry;
      weights[to] = tail[i].weight;
    }
    remaining -= old_end + shift - to;
    move_right(offsets[w], old_end, static_cast<std::uint32_t>(remaining));
    list = {};
    span_end = w;
  }
  std::fill(tail_words.begin(), tail_words.end(), 0);
  arena.reset();
  tail_postings = 0;
  tail_first_entry = static_cast<EntryId>(alive.size());
  postings = merged;
  dead_postings = 0;
}

Database::Database(Vocabulary vocabulary, DatabaseOptions options)
    : impl_(std::make_unique<Impl>(std::move(vocabulary), options)) {}
Database::Database(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Database::Database(Database&&) noexcept = default;
Database& Database::operator=(Database&&) noexcept = default;
Database::~Database() = default;

EntryId Database::add(const DescriptorView& descriptors) {
  BowVector bow;
  FeatureVector features;
  if (impl_->options.direct_index)
    impl_->vocabulary.transform(descriptors, bow, features, impl_->options.direct_index_levels_up);
  else
    impl_->vocabulary.transform(descriptors, bow);
  std::unique_lock lock(impl_->mutex);
  const EntryId entry = impl_->append(bow, features);
  impl_->merge_if_worthwhile();
  return entry;
}

EntryId Database::add(const BowVector& bow, const FeatureVector& features) {
  check_bow(bow, impl_->vocabulary, "Database::add");
  if (impl_->options.direct_index && !features.empty() &&
      features.node(features.size() - 1) >= impl_->vocabulary.node_count())
    throw InvalidArgument("Database::add: feature vector node " +
                          std::to_string(features.node(features.size() - 1)) +
                          " is outside the vocabulary (" +
                          std::to_string(impl_->vocabulary.node_count()) + " nodes)");
  std::unique_lock lock(impl_->mutex);
  const EntryId entry = impl_->append(bow, features);
  impl_->merge_if_worthwhile();
  return entry;
}

std::vector<QueryResult> Database::query(const BowVector& bow, std::size_t max_results,
                                         EntryId max_entry_id) const {
  check_bow(bow, impl_->vocabulary, "Database::query");
  std::vector<QueryResult> results;
  if (bow.empty() || max_results == 0) return results;
  const Scoring scoring = impl_->vocabulary.scoring();
  const double base = detail::score_base(scoring, bow);

  std::shared_lock lock(impl_->mutex);
  const std::size_t entry_count = impl_->alive.size();
  if (entry_count == 0) return results;
  QueryScratch& buffers = scratch;
  if (buffers.accumulators.size() < entry_count) buffers.accumulators.resize(entry_count);
  // accumulate() may write one element past the last new id.
  if (buffers.touched.size() < entry_count + 1) buffers.touched.resize(entry_count + 1);
  const EntryId last_entry = std::min<EntryId>(max_entry_id, static_cast<EntryId>(entry_count - 1));
  const IndexView index{impl_->main_offsets.empty() ? nullptr : impl_->main_offsets.data(),
                        impl_->main_ids.data(), impl_->main_weights.data(),
                        impl_->tail_lists.data(), &impl_->arena};
  const std::size_t touched = accumulate(scoring, index, bow, last_entry,
                                         buffers.accumulators.data(), buffers.touched.data());

  // Collecting candidates also zeroes the accumulators for the next query;
  // reserve first so nothing can throw with dirty accumulators.
  std::vector<QueryResult>& candidates = buffers.candidates;
  candidates.clear();
  try {
    candidates.reserve(touched);
  } catch (...) {
    for (std::size_t i = 0; i < touched; ++i) buffers.accumulators[buffers.touched[i]] = {};
    throw;
  }
  for (std::size_t i = 0; i < touched; ++i) {
    const EntryId entry = buffers.touched[i];
    Accumulator& accumulator = buffers.accumulators[entry];
    if (impl_->alive[entry] != 0)
      candidates.push_back(
          {entry, detail::finish_score(scoring, accumulator.sum, base), accumulator.shared});
    accumulator = {};
  }
  lock.unlock();

  const BetterResult better{scoring == Scoring::kKL};
  if (candidates.size() > max_results) {
    std::nth_element(candidates.begin(),
                     candidates.begin() + static_cast<std::ptrdiff_t>(max_results),
                     candidates.end(), better);
    candidates.resize(max_results);
  }
  std::sort(candidates.begin(), candidates.end(), better);
  results.assign(candidates.begin(), candidates.end());
  return results;
}

void Database::remove(EntryId entry) {
  std::unique_lock lock(impl_->mutex);
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::remove: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  impl_->alive[entry] = 0;
  --impl_->live_entries;
  impl_->dead_postings += impl_->word_counts[entry];
  if (!impl_->direct.empty()) impl_->direct[entry] = {};
  if (!impl_->labels.empty()) std::string().swap(impl_->labels[entry]);
  impl_->merge_if_worthwhile();
}

bool Database::contains(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  return impl_->is_live(entry);
}

FeatureVector Database::feature_vector(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  if (!impl_->options.direct_index)
    throw InvalidArgument("Database::feature_vector: this database keeps no direct index");
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::feature_vector: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  return impl_->direct[entry].unpack();
}

void Database::set_label(EntryId entry, std::string label) {
  std::unique_lock lock(impl_->mutex);
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::set_label: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  if (impl_->labels.size() < impl_->alive.size()) impl_->labels.resize(impl_->alive.size());
  impl_->labels[entry] = std::move(label);
}

std::string Database::label(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::label: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  return impl_->labels.empty() ? std::string() : impl_->labels[entry];
}

std::size_t Database::size() const {
  std::shared_lock lock(impl_->mutex);
  return impl_->live_entries;
}

EntryId Database::next_entry_id() const {
  std::shared_lock lock(impl_->mutex);
  return static_cast<EntryId>(impl_->alive.size());
}

void Database::clear() {
  std::unique_lock lock(impl_->mutex);
  std::vector<std::uint32_t>().swap(impl_->main_offsets);
  impl_->main_ids.resize(0);
  impl_->main_weights.resize(0);
  std::fill(impl_->tail_lists.begin(), impl_->tail_lists.end(), detail::TailList{});
  std::fill(impl_->tail_words.begin(), impl_->tail_words.end(), 0);
  impl_->arena.clear();
  impl_->tail_postings = 0;
  impl_->tail_first_entry = 0;
  std::vector<std::uint8_t>().swap(impl_->alive);
  std::vector<std::uint32_t>().swap(impl_->word_counts);
  std::vector<detail::PackedFeatureVector>().swap(impl_->direct);
  std::vector<std::string>().swap(impl_->labels);
  impl_->live_entries = 0;
  impl_->postings = 0;
  impl_->dead_postings = 0;
}

std::size_t Database::memory_usage() const {
  std::shared_lock lock(impl_->mutex);
  const Impl& impl = *impl_;
  std::size_t bytes = impl.main_offsets.capacity() * sizeof(std::uint32_t) +
                      impl.main_ids.size() * sizeof(EntryId) +
                      impl.main_weights.size() * sizeof(float) +
                      impl.tail_lists.capacity() * sizeof(detail::TailList) +
                      impl.tail_words.capacity() * sizeof(std::uint64_t) + impl.alive.capacity() +
                      impl.word_counts.capacity() * sizeof(std::uint32_t) +
                      impl.direct.capacity() * sizeof(detail::PackedFeatureVector) +
                      impl.labels.capacity() * sizeof(std::string);
  bytes += impl.arena.memory_usage();
  for (const auto& features : impl.direct) bytes += features.memory_usage();
  for (const auto& label : impl.labels)
    if (label.capacity() > 15) bytes += label.capacity() + 1;  // beyond the small-string buffer
  return bytes;
}

const Vocabulary& Database::vocabulary() const noexcept {
  return impl_->vocabulary;
}
const DatabaseOptions& Database::options() const noexcept {
  return impl_->options;
}

}  // namespace binbow
