// The image database: posting lists and the packed direct index. Queries
// live in database_query.cpp, the .bbdb format in database_file.cpp.
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

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

#include "binbow/error.h"
#include "core/database_impl.h"
#include "core/little_endian.h"

namespace binbow {

namespace detail {

void populate(void* data, std::size_t bytes) noexcept {
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
  constexpr std::size_t kWorthACall = std::size_t{2} << 20;
  if (bytes < kWorthACall) return;
  const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  const auto begin = (reinterpret_cast<std::uintptr_t>(data) + page - 1) & ~(page - 1);
  const auto end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(page - 1);
  // Older kernels refuse the advice: the pages then fault in as they are written.
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_POPULATE_WRITE);
#else
  (void)data;
  (void)bytes;
#endif
}

void* allocate_huge(std::size_t bytes) {
  constexpr std::size_t kHugePage = std::size_t{2} << 20;
  void* data = std::aligned_alloc(kHugePage, bytes);
  if (data == nullptr) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  madvise(data, bytes, MADV_HUGEPAGE);  // only advice: 4 KiB pages otherwise
#endif
  return data;
}

std::uint32_t PostingArena::new_chunk(std::size_t postings) {
  // Addresses are 32 bits: chunk index, then kChunkBits of position.
  if (chunks_.size() >= (std::size_t{1} << (32 - kChunkBits)))
    throw InvalidArgument("Database: the tail outgrew its 32 GiB of addresses");
  chunk_starts_.reserve(chunks_.size() + 1);
  chunk_postings_.reserve(chunks_.size() + 1);
  // Left uninitialised; a block larger than a chunk gets a chunk of its own,
  // whose size is rounded up to huge pages.
  const std::size_t huge_postings = (std::size_t{2} << 20) / sizeof(TailPosting);
  postings = (postings + huge_postings - 1) / huge_postings * huge_postings;
  chunks_.emplace_back(static_cast<TailPosting*>(allocate_huge(postings * sizeof(TailPosting))));
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

PackedFeatureVector::PackedFeatureVector(const FeatureVector& features)
    : node_count_(static_cast<std::uint32_t>(features.size())),
      feature_count_(static_cast<std::uint32_t>(features.feature_count())) {
  const auto& indices = features.feature_indices();
  bool partition = node_count_ <= 0x10000;
  if (partition) {
    // Every index below the count and none twice: a branch-free pass, a
    // byte per index so that no store waits for the one before (neighbours
    // would share a word of a bit set).
    std::vector<std::uint8_t> seen(std::size_t{feature_count_} + 1, 0);
    const std::size_t beyond = feature_count_;  // out-of-range indices land here
    std::uint8_t repeated = 0;
    for (std::uint32_t index : indices) {
      const std::size_t at = index < feature_count_ ? index : beyond;
      repeated |= seen[at];
      seen[at] = 1;
    }
    partition = repeated == 0 && seen[beyond] == 0;
  }
  if (partition) {
    layout_ = node_count_ <= 0x80    ? Layout::kPartition7
              : node_count_ <= 0x100 ? Layout::kPartition8
                                     : Layout::kPartition16;
  } else {
    const bool wide =
        feature_count_ > 0xFFFF ||
        std::any_of(indices.begin(), indices.end(), [](std::uint32_t i) { return i > 0xFFFF; });
    layout_ = wide ? Layout::kRows32 : Layout::kRows16;
  }
  // Node ids are increasing: each is stored as its step from the previous
  // one (the first from 0), 7 bits per byte (LEB128), or, when shorter, each
  // run of consecutive ids as the step to its first from the end of the
  // previous run (from 0) and its length - 1. Siblings are consecutive ids:
  // a direct index 4 levels up a k=10 L=6 tree takes ~1.2 bytes per node as
  // steps, ~0.4 as runs, against 4 for the ids.
  const auto leb128_bytes = [](std::uint32_t value) {
    std::uint32_t bytes = 1;
    for (; value >= 0x80; value >>= 7) ++bytes;
    return bytes;
  };
  const auto for_each_run = [&](const auto& visit) {
    NodeId end = 0;  // of the previous run
    for (std::size_t node = 0; node < node_count_;) {
      std::size_t last = node;
      while (last + 1 < node_count_ && features.node(last + 1) == features.node(last) + 1) ++last;
      visit(features.node(node) - end, static_cast<std::uint32_t>(last - node));
      end = features.node(last) + 1;
      node = last + 1;
    }
  };
  std::uint32_t step_bytes = 0, run_bytes = 0;
  for (std::size_t node = 0; node < node_count_; ++node)
    step_bytes += leb128_bytes(features.node(node) - (node > 0 ? features.node(node - 1) : 0));
  for_each_run([&](std::uint32_t step, std::uint32_t more) {
    run_bytes += leb128_bytes(step) + leb128_bytes(more);
  });
  node_runs_ = run_bytes < step_bytes;
  node_bytes_ = node_runs_ ? run_bytes : step_bytes;
  bytes_.reset(new std::uint8_t[packed_size()]);
  std::uint8_t* out = bytes_.get();
  const auto put_leb128 = [&](std::uint32_t value) {
    for (; value >= 0x80; value >>= 7) *out++ = static_cast<std::uint8_t>((value & 0x7F) | 0x80);
    *out++ = static_cast<std::uint8_t>(value);
  };
  if (node_runs_) {
    for_each_run([&](std::uint32_t step, std::uint32_t more) {
      put_leb128(step);
      put_leb128(more);
    });
  } else {
    for (std::size_t node = 0; node < node_count_; ++node)
      put_leb128(features.node(node) - (node > 0 ? features.node(node - 1) : 0));
  }
  if (layout_ == Layout::kPartition7) {
    // Feature f's 7 bits start at bit 7 f, from the low bit of each byte:
    // each feature's node position, then eight features per 7 bytes.
    std::vector<std::uint8_t> slots((std::size_t{feature_count_} + 7) / 8 * 8, 0);
    for (std::size_t node = 0; node < node_count_; ++node)
      for (std::uint32_t index : features.features(node))
        slots[index] = static_cast<std::uint8_t>(node);
    std::uint8_t* const end = bytes_.get() + packed_size();
    for (std::size_t f = 0; f < slots.size(); f += 8, out += 7) {
      std::uint64_t eight = 0;
      for (std::size_t k = 0; k < 8; ++k) eight |= std::uint64_t{slots[f + k]} << (7 * k);
      std::memcpy(out, &eight, std::min<std::size_t>(7, static_cast<std::size_t>(end - out)));
    }
    return;
  }
  if (partition) {
    const std::size_t width = layout_ == Layout::kPartition8 ? 1 : 2;
    for (std::size_t node = 0; node < node_count_; ++node) {
      const auto slot = static_cast<std::uint16_t>(node);
      if (width == 1) {
        for (std::uint32_t index : features.features(node))
          out[index] = static_cast<std::uint8_t>(slot);
      } else {
        for (std::uint32_t index : features.features(node))
          std::memcpy(out + std::size_t{index} * 2, &slot, 2);  // little-endian
      }
    }
    return;
  }
  const std::size_t width = layout_ == Layout::kRows32 ? 4 : 2;
  const auto put = [&](std::uint32_t v) {
    std::memcpy(out, &v, width);  // little-endian: the low bytes
    out += width;
  };
  for (std::size_t i = 1; i <= node_count_; ++i) put(features.offsets()[i]);
  for (std::uint32_t index : indices) put(index);
}

std::size_t PackedFeatureVector::packed_size() const noexcept {
  const std::size_t nodes = node_bytes_;
  switch (layout_) {
    case Layout::kPartition7:
      return nodes + (std::size_t{feature_count_} * 7 + 7) / 8;
    case Layout::kPartition8:
      return nodes + feature_count_;
    case Layout::kPartition16:
      return nodes + std::size_t{feature_count_} * 2;
    case Layout::kRows16:
      return nodes + (std::size_t{node_count_} + feature_count_) * 2;
    case Layout::kRows32:
      return nodes + (std::size_t{node_count_} + feature_count_) * 4;
  }
  return 0;
}

void PackedFeatureVector::encode(std::uint8_t* out) const noexcept {
  out[0] = static_cast<std::uint8_t>(static_cast<unsigned>(layout_) | (node_runs_ ? kNodeRuns : 0));
  store_le<std::uint32_t>(out + 1, node_bytes_);
  if (packed_size() > 0) std::memcpy(out + 5, bytes_.get(), packed_size());
}

bool PackedFeatureVector::read_leb128(const std::uint8_t*& at, const std::uint8_t* end,
                                      std::uint64_t& value) noexcept {
  value = 0;
  for (unsigned shift = 0; shift < 35; shift += 7) {
    if (at == end) return false;
    const std::uint8_t byte = *at++;
    value |= std::uint64_t{byte & 0x7Fu} << shift;
    if ((byte & 0x80) == 0) return true;
  }
  return false;
}

template <class Visit>
bool PackedFeatureVector::for_each_node(const Visit& visit) const {
  const std::uint8_t* at = bytes_.get();
  const std::uint8_t* const end = at + node_bytes_;
  std::uint64_t id = 0;
  for (std::uint32_t node = 0; node < node_count_;) {
    std::uint64_t step, more = 0;
    if (!read_leb128(at, end, step) || (node_runs_ && !read_leb128(at, end, more))) return false;
    // Steps after the first are at least 1 (runs: from the previous run's end).
    if (node > 0 && step == 0 && !node_runs_) return false;
    id += step;
    if (more >= node_count_ - node || id + more > 0xFFFFFFFFu) return false;
    for (std::uint64_t i = 0; i <= more; ++i, ++node) visit(static_cast<NodeId>(id + i));
    if (node_runs_) id += more + 1;
  }
  return at == end;
}

PackedFeatureVector PackedFeatureVector::decode(const std::uint8_t* data, std::size_t size,
                                                std::uint32_t node_count,
                                                std::uint32_t feature_count,
                                                std::uint64_t node_limit) {
  if (size < 5) throw InvalidArgument("shorter than its layout");
  PackedFeatureVector packed;
  packed.node_count_ = node_count;
  packed.feature_count_ = feature_count;
  const unsigned layout = data[0] & ~kNodeRuns;
  if (layout > static_cast<unsigned>(Layout::kPartition7))
    throw InvalidArgument("unknown layout " + std::to_string(data[0]));
  packed.layout_ = static_cast<Layout>(layout);
  packed.node_runs_ = (data[0] & kNodeRuns) != 0;
  packed.node_bytes_ = load_le<std::uint32_t>(data + 1);
  const bool partition = packed.partition();
  const std::uint32_t most_nodes = packed.layout_ == Layout::kPartition7   ? 0x80u
                                   : packed.layout_ == Layout::kPartition8 ? 0x100u
                                                                           : 0x10000u;
  if (partition && node_count > most_nodes) throw InvalidArgument("too many nodes for its layout");
  if (packed.node_bytes_ > size - 5 || size - 5 != packed.packed_size())
    throw InvalidArgument(std::to_string(size - 5) + " bytes, not what its " +
                          std::to_string(node_count) + " nodes and " +
                          std::to_string(feature_count) + " features take");
  packed.bytes_.reset(new std::uint8_t[size - 5]);
  if (size > 5) std::memcpy(packed.bytes_.get(), data + 5, size - 5);
  NodeId largest = 0;
  if (!packed.for_each_node([&](NodeId id) { largest = id; }))
    throw InvalidArgument(
        "node ids are cut short, too large, not strictly increasing or followed by stray bytes");
  if (node_count > 0 && largest >= node_limit)
    throw InvalidArgument("node " + std::to_string(largest) + " is out of range");
  if (partition) {
    // Every feature names a node, and every node has a feature.
    std::vector<std::uint8_t> used(node_count, 0);
    for (std::size_t f = 0; f < feature_count; ++f) {
      const std::uint32_t slot = packed.slot(f);
      if (slot >= node_count) throw InvalidArgument("a feature names no node");
      used[slot] = 1;
    }
    if (std::find(used.begin(), used.end(), 0) != used.end())
      throw InvalidArgument("a node has no features");
    // The bits after the last feature's are zero: one encoding per vector.
    const std::size_t used_bits = std::size_t{7} * feature_count;
    if (packed.layout_ == Layout::kPartition7 && used_bits % 8 != 0 &&
        (packed.bytes_[size - 6] >> (used_bits % 8)) != 0)
      throw InvalidArgument("stray bits after the last feature");
  } else {
    const std::size_t width = packed.layout_ == Layout::kRows32 ? 4 : 2;
    std::uint32_t previous = 0;
    for (std::size_t node = 0; node < node_count; ++node) {
      const std::uint32_t end = packed.value(packed.node_bytes_ + node * width, width);
      if (end <= previous) throw InvalidArgument("a node has no features");
      previous = end;
    }
    if (previous != feature_count) throw InvalidArgument("node offsets do not end at its features");
  }
  return packed;
}

FeatureVector PackedFeatureVector::unpack() const {
  std::vector<NodeId> nodes;
  nodes.reserve(node_count_);
  for_each_node([&](NodeId id) { nodes.push_back(id); });
  const std::size_t nodes_bytes = node_bytes_;
  std::vector<std::uint32_t> offsets(std::size_t{node_count_} + 1, 0);
  std::vector<std::uint32_t> indices(feature_count_);
  if (partition()) {
    // Counting sort of the features by node; increasing index within a node.
    for (std::size_t f = 0; f < feature_count_; ++f) ++offsets[slot(f) + 1];
    for (std::size_t i = 0; i < node_count_; ++i) offsets[i + 1] += offsets[i];
    std::vector<std::uint32_t> next(offsets.begin(), offsets.end() - 1);
    for (std::uint32_t f = 0; f < feature_count_; ++f) indices[next[slot(f)]++] = f;
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

void check_direct_index_levels(const DatabaseOptions& options) {
  if (options.direct_index_levels_up > kMaxDirectIndexLevelsUp)
    throw InvalidArgument("Database: direct_index_levels_up is " +
                          std::to_string(options.direct_index_levels_up) + ", at most " +
                          std::to_string(kMaxDirectIndexLevelsUp) + " can be saved");
}

// Over word ids, the rows start with this many words and double as needed.

std::string no_entry_message(EntryId entry, EntryId next) {
  if (entry >= next)
    return "entry " + std::to_string(entry) + " does not exist (the database has ids below " +
           std::to_string(next) + ")";
  return "entry " + std::to_string(entry) + " was removed";
}

}  // namespace

Database::Impl::Impl(Vocabulary vocabulary_in, DatabaseOptions options_in)
    : vocabulary(std::move(vocabulary_in)), options(options_in) {
  if (vocabulary.empty()) throw InvalidArgument("Database: the vocabulary is empty");
  check_direct_index_levels(options);
  scoring = vocabulary.scoring();
  lay_out(vocabulary.word_count());
}

Database::Impl::Impl(Scoring scoring_in, DatabaseOptions options_in)
    : options(options_in), scoring(scoring_in), over_word_ids(true) {
  check_direct_index_levels(options);
  lay_out(detail::kInitialWordCapacity);
}

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

Database::Database(Vocabulary vocabulary, DatabaseOptions options)
    : impl_(std::make_unique<Impl>(std::move(vocabulary), options)) {}
Database::Database(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Database Database::over_word_ids(Scoring scoring, DatabaseOptions options) {
  return Database(std::make_unique<Impl>(scoring, options));
}
Database::Database(Database&&) noexcept = default;
Database& Database::operator=(Database&&) noexcept = default;
Database::~Database() = default;

void Database::Impl::store_label(EntryId entry, std::string label) {
  if (labels.size() < alive.size()) labels.resize(alive.size());
  labels[entry] = std::move(label);
}

EntryId Database::add(const DescriptorView& descriptors, std::string label) {
  if (impl_->over_word_ids)
    throw InvalidArgument(
        "Database::add: a database over word ids has no vocabulary to transform descriptors");
  BowVector bow;
  FeatureVector features;
  if (impl_->options.direct_index)
    impl_->vocabulary.transform(descriptors, bow, features, impl_->options.direct_index_levels_up);
  else
    impl_->vocabulary.transform(descriptors, bow);
  std::unique_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  const EntryId entry = impl_->append(bow, features);
  impl_->journal.record_add(entry, bow, impl_->options.direct_index ? features : FeatureVector(),
                            label);
  if (!label.empty()) impl_->store_label(entry, std::move(label));
  impl_->freeze_tail_if_full();
  return entry;
}

EntryId Database::add(const BowVector& bow, const FeatureVector& features, std::string label) {
  if (impl_->over_word_ids) {
    std::unique_lock lock(impl_->mutex);
    impl_->throw_if_damaged();
    if (!bow.empty()) impl_->grow_words(std::size_t{bow[bow.size() - 1].word} + 1);
    const EntryId entry = impl_->append(bow, features);
    impl_->journal.record_add(entry, bow, impl_->options.direct_index ? features : FeatureVector(),
                              label);
    if (!label.empty()) impl_->store_label(entry, std::move(label));
    impl_->freeze_tail_if_full();
    return entry;
  }
  // append checks the values.
  detail::check_bow_words(bow, impl_->vocabulary, "Database::add");
  if (impl_->options.direct_index && !features.empty() &&
      features.node(features.size() - 1) >= impl_->vocabulary.node_count())
    throw InvalidArgument("Database::add: feature vector node " +
                          std::to_string(features.node(features.size() - 1)) +
                          " is outside the vocabulary (" +
                          std::to_string(impl_->vocabulary.node_count()) + " nodes)");
  std::unique_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  const EntryId entry = impl_->append(bow, features);
  impl_->journal.record_add(entry, bow, impl_->options.direct_index ? features : FeatureVector(),
                            label);
  if (!label.empty()) impl_->store_label(entry, std::move(label));
  impl_->freeze_tail_if_full();
  return entry;
}

void Database::remove(EntryId entry) {
  std::unique_lock lock(impl_->mutex);
  // The entry's postings are counted by the file's check.
  impl_->merge_file_check();
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::remove: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  impl_->alive[entry] = 0;
  --impl_->live_entries;
  impl_->journal.record_remove(entry);
  // An entry without postings has nothing to drop, and may lie where no
  // segment is left (one whose postings were all removed is dropped).
  const std::size_t segment =
      impl_->word_counts[entry] == 0 ? impl_->segments.size() : impl_->segment_of(entry);
  if (segment == impl_->segments.size()) {
    impl_->tail_dead_postings += impl_->word_counts[entry];
  } else {
    detail::Segment& thinned = *impl_->segments[segment];
    thinned.dead_postings += impl_->word_counts[entry];
    if (thinned.dead_postings * 3 > thinned.postings()) impl_->compact(segment);
  }
  if (!impl_->direct.empty()) impl_->direct[entry] = {};
  if (impl_->forward_built) impl_->forward.drop(entry);
  if (!impl_->labels.empty()) std::string().swap(impl_->labels[entry]);
}

bool Database::contains(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  return impl_->is_live(entry);
}

FeatureVector Database::feature_vector(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  if (!impl_->options.direct_index)
    throw InvalidArgument("Database::feature_vector: this database keeps no direct index");
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::feature_vector: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  if (entry >= impl_->loaded_direct.entries()) return impl_->direct[entry].unpack();
  try {
    return impl_->loaded_direct.decode(entry).unpack();
  } catch (const InvalidArgument& e) {
    // Only in a damaged file, whose check has not ended yet.
    throw FileError(
        impl_->loaded_direct.name,
        "the direct index of entry " + std::to_string(entry) + " is damaged (" + e.what() + ")");
  }
}

void Database::set_label(EntryId entry, std::string label) {
  std::unique_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::set_label: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  impl_->journal.record_label(entry, label);
  impl_->store_label(entry, std::move(label));
}

std::string Database::label(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::label: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  return impl_->labels.empty() ? std::string() : impl_->labels[entry];
}

std::size_t Database::size() const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  return impl_->live_entries;
}

EntryId Database::next_entry_id() const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  return static_cast<EntryId>(impl_->alive.size());
}

void Database::clear() {
  std::unique_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  impl_->journal.record_clear();
  impl_->file_check.reset();  // stops it: nothing of the file is left
  impl_->file_check_merged = true;
  impl_->loaded_direct = {};
  std::vector<std::unique_ptr<detail::Segment>>().swap(impl_->segments);
  std::fill(impl_->tail_lists.begin(), impl_->tail_lists.end(), detail::TailList{});
  std::fill(impl_->first_block_logs.begin(), impl_->first_block_logs.end(), detail::kFirstBlockLog);
  impl_->arena.clear();
  impl_->tail_postings = 0;
  impl_->tail_dead_postings = 0;
  impl_->tail_first_entry = 0;
  std::vector<std::uint8_t>().swap(impl_->alive);
  std::vector<std::uint32_t>().swap(impl_->word_counts);
  std::vector<double>().swap(impl_->divisors);
  std::vector<detail::PackedFeatureVector>().swap(impl_->direct);
  std::vector<std::string>().swap(impl_->labels);
  impl_->live_entries = 0;
  impl_->values = {};
  impl_->forward.clear();
}

std::size_t Database::memory_usage() const {
  std::shared_lock lock(impl_->mutex);
  const Impl& impl = *impl_;
  std::size_t bytes = impl.segments.capacity() * sizeof(impl.segments[0]) +
                      impl.tail_lists.capacity() * sizeof(detail::TailList) +
                      impl.first_block_logs.capacity() + impl.alive.capacity() +
                      impl.word_counts.capacity() * sizeof(std::uint32_t) +
                      impl.divisors.capacity() * sizeof(double) +
                      impl.direct.capacity() * sizeof(detail::PackedFeatureVector) +
                      impl.loaded_direct.offsets.capacity() * sizeof(std::uint64_t) +
                      impl.labels.capacity() * sizeof(std::string);
  // A loaded database's rows and direct index are the file's pages, counted
  // too: what the index occupies in memory once read (see Database::load).
  for (const auto& segment : impl.segments)
    bytes += sizeof(*segment) + segment->offsets.capacity() * sizeof(std::uint32_t) +
             segment->bytes.size();
  if (!impl.loaded_direct.offsets.empty())
    bytes += static_cast<std::size_t>(impl.loaded_direct.offsets.back());
  bytes += impl.arena.memory_usage();
  if (impl.forward_built) bytes += impl.forward.memory_usage();
  bytes += impl.journal.memory_usage();
  for (const auto& features : impl.direct) bytes += features.memory_usage();
  for (const auto& label : impl.labels)
    if (label.capacity() > 15) bytes += label.capacity() + 1;  // beyond the small-string buffer
  return bytes;
}

// save_incremental's append (database_journal.cpp) without its fallback to a
// full save.
bool Database::append_journal(const std::string& path) const {
  std::shared_lock lock(impl_->mutex);
  std::lock_guard<std::mutex> saving(impl_->journal.mutex);
  return impl_->journal.append(path);
}

const Vocabulary& Database::vocabulary() const noexcept {
  return impl_->vocabulary;
}
Scoring Database::scoring() const noexcept {
  return impl_->scoring;
}
const DatabaseOptions& Database::options() const noexcept {
  return impl_->options;
}

}  // namespace binbow
