// The state behind binbow::Database, shared by its index (database_tail.cpp,
// database_segments.cpp), queries, journal and .bbdb reader and writer.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"
#include "core/scoring.h"
#include "database/background_check.h"
#include "database/count_form.h"
#include "database/database_journal.h"
#include "database/forward_index.h"
#include "database/writer_priority_mutex.h"

namespace binbow::detail {

// A segment's rows are ordered by group of words: word w is in group
// w mod 2^kGroupBits (see RowOrder).
constexpr unsigned kGroupBits = 16;
// The word-id capacity a database over word ids starts with.
constexpr std::size_t kInitialWordCapacity = std::size_t{1} << 16;
constexpr std::uint32_t group_of(WordId word) noexcept {
  return word & ((1u << kGroupBits) - 1);
}

// The tail keeps one list per 2^kTailListShift consecutive groups (4096
// lists for 65,536 groups): their 8-byte heads (32 KiB) and the cache lines
// their next postings go to (256 KiB) stay in a core's cache while images
// are added, so that appends miss the cache once per 64 bytes of postings
// (with a list per group, twice per posting). A list's rows are consecutive
// (RowOrder), so freezing the tail writes the rows sequentially, a list at
// a time within the cache. Fewer groups per list where the word capacity
// needs it: a tail key holds the entry's 16 bits and the word's row among
// its list's.
constexpr unsigned kTailListShift = 4;
constexpr unsigned kTailEntryBits = 16;

// The order of a segment's rows (and of a .bbdb's): by group, then word
// (w, w + 65,536, ...), so that a tail list's rows are consecutive.
// Identity for vocabularies of up to 65,536 words.
class RowOrder {
 public:
  RowOrder() = default;
  explicit RowOrder(std::size_t word_count) noexcept
      : per_group_(static_cast<std::uint32_t>(word_count >> kGroupBits)),
        longer_groups_(group_of(static_cast<WordId>(word_count))) {}
  // Groups [0, longer_groups_) have per_group_ + 1 words, the others per_group_.
  std::uint32_t group_start(std::uint32_t group) const noexcept {
    return group * per_group_ + std::min(group, longer_groups_);
  }
  std::uint32_t row(WordId word) const noexcept {
    return group_start(group_of(word)) + (word >> kGroupBits);
  }
  // Calls visit(row, word) for the words below `word_count` in row order
  // (the inverse of row() for RowOrder(word_count)).
  template <class Visit>
  static void for_each_row(std::size_t word_count, const Visit& visit) {
    const std::size_t groups = std::min<std::size_t>(word_count, std::size_t{1} << kGroupBits);
    std::uint32_t row = 0;
    for (std::size_t group = 0; group < groups; ++group)
      for (std::size_t word = group; word < word_count; word += groups, ++row)
        visit(row, static_cast<WordId>(word));
  }

 private:
  std::uint32_t per_group_ = 0;
  std::uint32_t longer_groups_ = 0;
};

// A posting of the tail: the entry (relative to the tail's first entry, so
// it fits) and the word's row among its list's in one key, then the
// weight. A list is in increasing entry order.
struct TailPosting {
  std::uint32_t key;  // (entry - tail_first_entry) << high_bits | the word's tail_row
  float weight;
};

// The tail postings of one list: where its block is in the arena, and how
// many postings it holds. A list's first block holds 2^first_block_log
// postings (the list's size when the tail was last frozen, so that most
// lists never move), and each time the list outgrows its block it moves to
// one twice as large: the block holds max(2^first_block_log, the smallest
// power of two ≥ size) postings (at least that many: undoing an append may
// leave more room, never less).
struct TailList {
  std::uint32_t block = 0;  // a PostingArena address; meaningless while size is 0
  std::uint32_t size = 0;
};

// The error for a BoW value that is not finite.
InvalidArgument non_finite_value(const char* what, WordId word);
// Throw InvalidArgument, naming `what`, for a word beyond the vocabulary or
// a value that is not finite.
void check_bow_words(const BowVector& bow, const Vocabulary& vocabulary, const char* what);
void check_bow_values(const BowVector& bow, const char* what);

constexpr unsigned kFirstBlockLog = 2;
constexpr bool tail_list_full(std::uint32_t size, unsigned first_block_log) noexcept {
  return size == 0 || (size >= (1u << first_block_log) && (size & (size - 1)) == 0);
}

// Storage of the tail's posting lists: blocks of 2^k postings carved
// from large chunks, with a free list per block size for the blocks that
// growing lists leave behind. Blocks are named by 32-bit addresses (chunk
// index, then position in the chunk) so a list's TailList is 8 bytes. The
// whole tail is dropped at once when it becomes a segment, so there is no
// per-list malloc, free or header.
class PostingArena {
 public:
  // 2^18 postings: 2 MiB chunks, aligned so that each is one huge page
  // where the kernel allows: appends write all over the tail, and with 4 KiB
  // pages most of them would also miss the TLB.
  static constexpr unsigned kChunkBits = 18;

  PostingArena() noexcept { clear(); }
  // A block for `capacity` postings (a power of two).
  std::uint32_t allocate(std::uint32_t capacity);
  void release(std::uint32_t block, std::uint32_t capacity) noexcept;
  // Forgets every block but keeps the chunks of the usual size for reuse:
  // the tail fills again after each freeze, and fresh memory costs a page
  // fault (about 2 µs in our VM) per 4 KiB.
  void reset() noexcept;
  void clear() noexcept;
  std::size_t memory_usage() const noexcept { return chunk_bytes_; }
  TailPosting* at(std::uint32_t block) const noexcept {
    return chunk_starts_[block >> kChunkBits] + (block & ((1u << kChunkBits) - 1));
  }
  TailPosting* const* chunk_starts() const noexcept { return chunk_starts_.data(); }

 private:
  static constexpr std::uint32_t kNoBlock = 0xFFFFFFFF;
  std::uint32_t new_chunk(std::size_t postings);

  struct Free {
    void operator()(TailPosting* chunk) const noexcept { std::free(chunk); }
  };
  std::vector<std::unique_ptr<TailPosting[], Free>> chunks_;
  std::vector<TailPosting*> chunk_starts_;
  std::vector<std::size_t> chunk_postings_;
  std::uint32_t free_lists_[33];  // per log2(capacity)
  std::uint32_t bump_ = 0;        // address of the next free posting
  std::size_t bump_left_ = 0;     // in postings, in the chunk of bump_
  // Chunks [spare_begin_, spare_end_) are kept from before the last reset
  // and not used yet.
  std::size_t spare_begin_ = 0;
  std::size_t spare_end_ = 0;
  std::size_t chunk_bytes_ = 0;
};

// Maps the pages of a fresh block of a few MiB or more in one system call
// (MADV_POPULATE_WRITE), before it is written, instead of a page fault per
// 4 KiB as merges write it (adds 2-10% faster at 300,000 real images).
// Does nothing where the kernel cannot.
void populate(void* data, std::size_t bytes) noexcept;
// `bytes` (a multiple of 2 MiB) of memory aligned to 2 MiB, backed by huge
// pages where the kernel allows; throws std::bad_alloc. Free with std::free.
void* allocate_huge(std::size_t bytes);

// A trivially copyable array in one malloc'd block, resized with realloc: a
// segment's arrays are allocated at their final size without initialising
// elements that are written next, and shrink in place when compacted.
template <typename T>
class GrowableArray {
 public:
  GrowableArray() = default;
  GrowableArray(const GrowableArray&) = delete;
  GrowableArray& operator=(const GrowableArray&) = delete;
  ~GrowableArray() { std::free(data_); }

  T* data() noexcept { return data_; }
  const T* data() const noexcept { return data_; }
  std::size_t size() const noexcept { return size_; }
  // Keeps the first min(size, n) elements; the others are uninitialised.
  // Growing throws std::bad_alloc, leaving the array as it was; shrinking
  // never throws (it keeps the larger block if realloc fails).
  void resize(std::size_t n) {
    if (n == size_) return;
    if (n == 0) {
      std::free(data_);
      data_ = nullptr;
      size_ = 0;
      return;
    }
    void* moved = std::realloc(data_, n * sizeof(T));
    if (moved != nullptr)
      data_ = static_cast<T*>(moved);
    else if (n > size_)
      throw std::bad_alloc();
    if (n > size_) populate(data_ + size_, (n - size_) * sizeof(T));
    size_ = n;
  }
  void swap(GrowableArray& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
  }
  void assign(const T* values, std::size_t n) {
    resize(n);
    if (n > 0) std::memcpy(data_, values, n * sizeof(T));
  }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

// A segment's row bytes: owned (a GrowableArray), or a read-only view of
// the rows of a loaded .bbdb file, which `keeper` (the file's mapping) keeps
// alive: a loaded database costs no copy of its index, and the pages are the
// file's, shared with the page cache. Writing through a view (non-const
// data(), resize) first copies it into owned memory, so code that changes a
// segment (compaction) needs no special case.
class SegmentBytes {
 public:
  SegmentBytes() = default;
  const std::uint8_t* data() const noexcept { return view_ != nullptr ? view_ : owned_.data(); }
  std::uint8_t* data() {
    own();
    return owned_.data();
  }
  std::size_t size() const noexcept { return view_ != nullptr ? view_size_ : owned_.size(); }
  void resize(std::size_t n) {
    own();
    owned_.resize(n);
  }
  void swap(SegmentBytes& other) noexcept {
    owned_.swap(other.owned_);
    std::swap(view_, other.view_);
    std::swap(view_size_, other.view_size_);
    keeper_.swap(other.keeper_);
  }
  // Takes `other`'s bytes, owned; `other` gets these bytes if they were
  // owned, else none.
  void swap(GrowableArray<std::uint8_t>& other) noexcept {
    view_ = nullptr;
    view_size_ = 0;
    keeper_.reset();
    owned_.swap(other);
  }
  void view(const std::uint8_t* data, std::size_t size, std::shared_ptr<const void> keeper) {
    owned_.resize(0);
    view_ = data;
    view_size_ = size;
    keeper_ = std::move(keeper);
  }
  bool is_view() const noexcept { return view_ != nullptr; }

 private:
  void own() {
    if (view_ == nullptr) return;
    owned_.assign(view_, view_size_);
    view_ = nullptr;
    view_size_ = 0;
    keeper_.reset();
  }

  GrowableArray<std::uint8_t> owned_;
  const std::uint8_t* view_ = nullptr;
  std::size_t view_size_ = 0;
  std::shared_ptr<const void> keeper_;
};

// One entry's FeatureVector, packed. Node ids are the steps from the
// previous one (LEB128: siblings take a byte each). When every feature
// 0..n-1 sits under exactly one node (what transform produces), each feature
// just stores the position of its node: in 7 bits when there are at most 128
// nodes (a direct index 4 levels up a k=10 L=6 tree has at most 100: 7/8 of
// a byte per feature), 8 bits up to 256 nodes, else 16; otherwise the end offset of
// every node's features and the feature indices follow, 16 bit when they fit
// (images have fewer than 65,536 features), else 32 bit.
class PackedFeatureVector {
 public:
  PackedFeatureVector() = default;
  explicit PackedFeatureVector(const FeatureVector& features);
  FeatureVector unpack() const;
  std::uint32_t node_count() const noexcept { return node_count_; }
  std::uint32_t feature_count() const noexcept { return feature_count_; }
  std::size_t memory_usage() const noexcept { return packed_size(); }

  // The form a .bbdb (versions 2 and 3) stores: the layout (u8, with
  // kNodeRuns when the node ids are runs), the bytes of the node ids (u32),
  // then the packed bytes, little-endian.
  std::size_t encoded_size() const noexcept { return 5 + packed_size(); }
  void encode(std::uint8_t* out) const noexcept;
  // The inverse, for `node_count` nodes below `node_limit` and
  // `feature_count` features; throws InvalidArgument unless the bytes are
  // exactly an encoding of a valid FeatureVector.
  static PackedFeatureVector decode(const std::uint8_t* data, std::size_t size,
                                    std::uint32_t node_count, std::uint32_t feature_count,
                                    std::uint64_t node_limit);

 private:
  // Numbered as stored; kPartition7 came last.
  enum class Layout : std::uint8_t { kPartition8, kPartition16, kRows16, kRows32, kPartition7 };
  bool partition() const noexcept {
    return layout_ != Layout::kRows16 && layout_ != Layout::kRows32;
  }
  // The position of the node of feature `f` (partition layouts).
  std::uint32_t slot(std::size_t f) const noexcept {
    const std::size_t base = node_bytes_;
    if (layout_ == Layout::kPartition7) {
      const std::size_t bit = 7 * f;
      const std::size_t byte = base + bit / 8;
      std::uint32_t v = bytes_[byte];
      if (byte + 1 < packed_size()) v |= std::uint32_t{bytes_[byte + 1]} << 8;
      return (v >> (bit % 8)) & 0x7F;
    }
    return layout_ == Layout::kPartition8 ? value(base + f, 1) : value(base + 2 * f, 2);
  }
  // The little-endian value of `width` (1, 2 or 4) bytes at `byte_offset`.
  std::uint32_t value(std::size_t byte_offset, std::size_t width) const noexcept {
    const std::uint8_t* at = bytes_.get() + byte_offset;
    if (width == 1) return *at;
    if (width == 2) {
      std::uint16_t v;
      std::memcpy(&v, at, 2);
      return v;
    }
    std::uint32_t v;
    std::memcpy(&v, at, 4);
    return v;
  }
  static constexpr unsigned kNodeRuns = 0x80;  // in the stored layout byte
  // The LEB128 value at `at` (before `end`, at most 5 bytes), moving past it;
  // false if it is cut short or longer.
  static bool read_leb128(const std::uint8_t*& at, const std::uint8_t* end,
                          std::uint64_t& value) noexcept;
  // Calls visit(id) for the node ids in order; false unless the node bytes
  // are exactly node_count_ strictly increasing 32-bit ids.
  template <class Visit>
  bool for_each_node(const Visit& visit) const;
  // The packed size for the layout and widths, in bytes.
  std::size_t packed_size() const noexcept;

  // packed_size() bytes: 24 bytes per entry in all, the vector's own.
  std::unique_ptr<std::uint8_t[]> bytes_;
  std::uint32_t node_count_ = 0;
  std::uint32_t feature_count_ = 0;
  std::uint32_t node_bytes_ = 0;  // of the node ids, at the start of bytes_
  Layout layout_ = Layout::kPartition8;
  bool node_runs_ = false;
};

// The direct index of the entries a database was loaded with, left in the
// file's mapping (its encodings, as PackedFeatureVector::encode writes
// them) and decoded when asked for: loading allocates nothing per entry.
struct LoadedDirectIndex {
  std::shared_ptr<const void> keeper;   // the mapping
  std::string name;                     // the file's
  const std::uint8_t* sizes = nullptr;  // per entry: u32 nodes, u32 features, u32 bytes
  const std::uint8_t* data = nullptr;
  std::vector<std::uint64_t> offsets;  // of each entry's encoding in `data`, then the end
  std::uint64_t node_limit = 0;

  // Entries [0, entries()) are the file's.
  EntryId entries() const noexcept {
    return offsets.empty() ? 0 : static_cast<EntryId>(offsets.size() - 1);
  }
  std::uint32_t size_field(EntryId entry, unsigned field) const noexcept {
    std::uint32_t value;
    std::memcpy(&value, sizes + 12 * std::size_t{entry} + 4 * field, 4);
    return value;
  }
  const std::uint8_t* encoding(EntryId entry) const noexcept { return data + offsets[entry]; }
  std::size_t encoded_size(EntryId entry) const noexcept {
    return static_cast<std::size_t>(offsets[entry + 1] - offsets[entry]);
  }
  // Throws InvalidArgument unless the bytes are a valid encoding (they are
  // read whatever they hold: the file may not be verified yet).
  PackedFeatureVector decode(EntryId entry) const {
    return PackedFeatureVector::decode(encoding(entry), encoded_size(entry), size_field(entry, 0),
                                       size_field(entry, 1), node_limit);
  }
};

}  // namespace binbow::detail

namespace binbow {

namespace detail {

// A part of the inverted index: the postings of the entries
// [first_entry, end_entry) as rows by word (in RowOrder): one byte offset
// per word, then the row's bytes. An empty row has none; otherwise a header
// byte holds the row's gap width (1 if every gap of the row is below 256,
// else 2) and its kind, then come its postings in increasing entry order at
// a fixed stride: the gap from the previous entry (entry - previous - 1, the
// first from first_entry - 1; little-endian, of the row's width), then the
// value. In a count row (kCountRow), every posting's entry is in count form
// (its divisor, in Database::Impl::divisors, is above 0) and the value is
// the word's count in it (u8, ≥ 1): its weight is count_weight(the word's
// vocabulary weight, count, divisor), bit for bit what the entry was added
// with; 2-3 bytes per posting. Otherwise the value is the weight (f32,
// little-endian, unaligned): 5-6 bytes. A fixed stride lets a query read a
// row with no branch per posting, so the cache misses of its score sums
// overlap. A segment spans at most kSegmentSpan ids, so that 2 bytes hold
// any gap. A query pays one offset lookup per word and segment, small next
// to the postings it reads.
constexpr std::size_t kSegmentSpan = std::size_t{1} << 16;

// A query starts at most one thread per this many postings of the index
// (4M by default): a thread pays off only for large indexes. For tests: a
// lower value splits small indexes between threads.
std::atomic<std::size_t>& postings_per_query_thread();

constexpr std::size_t kWeightBytes = 4;
constexpr std::size_t kCountBytes = 1;
constexpr std::uint32_t kMaxRowCount = 0xFF;
constexpr std::size_t kRowHeaderBytes = 1;
constexpr std::size_t kMaxGapWidth = 2;
constexpr std::uint8_t kCountRow = 0x10;  // in the header, with the gap width
// What RowWriter needs per posting: a 2-byte gap and a weight.
constexpr std::size_t kWriterSlotBytes = kMaxGapWidth + kWeightBytes;

// The gap width of a row whose gaps OR to `gaps`.
constexpr std::size_t gap_width(std::uint32_t gaps) noexcept {
  return gaps < 0x100 ? 1 : 2;
}
// A row header's gap width, value bytes and posting stride.
constexpr std::size_t header_width(std::uint8_t header) noexcept {
  return header & 3;
}
constexpr bool header_counts(std::uint8_t header) noexcept {
  return (header & kCountRow) != 0;
}
constexpr std::size_t header_stride(std::uint8_t header) noexcept {
  return header_width(header) + (header_counts(header) ? kCountBytes : kWeightBytes);
}
// The bytes of a row of `postings` postings whose gaps OR to `gaps`.
constexpr std::size_t row_bytes(std::size_t postings, std::uint32_t gaps, bool counts) noexcept {
  return postings == 0 ? 0
                       : kRowHeaderBytes +
                             postings * (gap_width(gaps) + (counts ? kCountBytes : kWeightBytes));
}
inline void put_gap(std::uint8_t* out, std::size_t width, std::uint32_t gap) noexcept {
  out[0] = static_cast<std::uint8_t>(gap);
  if (width == 2) out[1] = static_cast<std::uint8_t>(gap >> 8);
}
// Writes a posting of an f32 row of gap width `width` at `out`; returns the byte after it.
inline std::uint8_t* put_posting(std::uint8_t* out, std::size_t width, std::uint32_t gap,
                                 float weight) noexcept {
  put_gap(out, width, gap);
  std::memcpy(out + width, &weight, kWeightBytes);  // little-endian hosts only (as the whole index)
  return out + width + kWeightBytes;
}
// The same, in a count row.
inline std::uint8_t* put_count_posting(std::uint8_t* out, std::size_t width, std::uint32_t gap,
                                       std::uint32_t count) noexcept {
  put_gap(out, width, gap);
  out[width] = static_cast<std::uint8_t>(count);
  return out + width + kCountBytes;
}
template <std::size_t kWidth>
inline std::uint32_t read_gap(const std::uint8_t* at) noexcept {
  return kWidth == 1 ? at[0] : std::uint32_t{at[0]} | std::uint32_t{at[1]} << 8;
}
inline std::uint32_t read_gap(const std::uint8_t* at, std::size_t width) noexcept {
  return width == 1 ? read_gap<1>(at) : read_gap<2>(at);
}
inline float read_weight(const std::uint8_t* at) noexcept {
  float weight;
  std::memcpy(&weight, at, kWeightBytes);
  return weight;
}
// The entry before a row's first, relative to first_entry: gaps are
// differences minus 1, in wrapping 32-bit arithmetic.
constexpr std::uint32_t kRowStart = ~std::uint32_t{0};

// The count of a posting of an entry in count form, from its weight and
// 1 / its word's weight: the weight is count_weight(word_weight, c, divisor)
// for a count c ≤ 255, within 2^-24 relatively, so the product is within
// 2^-15 of c (multiplying by the inverse adds ~2^-52: no division per
// posting as the tail is frozen).
inline std::uint32_t count_of(float weight, double inverse_word_weight, double divisor) noexcept {
  return static_cast<std::uint32_t>(static_cast<double>(weight) * divisor * inverse_word_weight +
                                    0.5);
}

// What turns a row's counts into weights: its word's vocabulary weight, and
// the divisors of the segment's entries (indexed relative to first_entry).
struct RowWeights {
  double word_weight = 0;
  const double* divisors = nullptr;
  float weight(std::uint32_t relative_entry, std::uint32_t count) const noexcept {
    return count_weight(word_weight, count, divisors[relative_entry]);
  }
};
// The same for every row of a segment.
struct SegmentWeights {
  const float* word_weights = nullptr;  // the vocabulary's; null over word ids (no counts)
  const double* divisors = nullptr;     // from the segment's first entry
  RowWeights row(WordId word) const noexcept {
    return {word_weights != nullptr ? static_cast<double>(word_weights[word]) : 0.0, divisors};
  }
};

// A posting's value as a row holds it: a count (1 to kMaxRowCount), or 0
// and the weight.
struct PostingValue {
  std::uint32_t count;
  float weight;  // meaningful when count is 0
};

// Writes a row from its postings alone: each with a 2-byte gap, narrowed to
// 1 byte by finish() when every gap allows, and with its count while every
// posting has one (a count row), else with its weight (the weights of the
// counts so far are then computed). Needs kRowHeaderBytes +
// kWriterSlotBytes per posting.
class RowWriter {
 public:
  // For a row of `word` in a segment whose counts `weights` computes.
  RowWriter(std::uint8_t* out, const SegmentWeights& weights, WordId word) noexcept
      : begin_(out), at_(out + kRowHeaderBytes), weights_(weights), word_(word) {}
  // `value` has a count of at most kMaxRowCount, or a weight.
  void put(std::uint32_t gap, PostingValue value) {
    entry_ += gap + 1;
    gaps_ |= gap;
    if (counts_ && value.count == 0) to_weights(gap);
    at_[0] = static_cast<std::uint8_t>(gap);
    at_[1] = static_cast<std::uint8_t>(gap >> 8);
    if (counts_) {
      at_[2] = static_cast<std::uint8_t>(value.count);
      at_ += kMaxGapWidth + kCountBytes;
      return;
    }
    const float weight = value.count != 0 ? row_.weight(entry_, value.count) : value.weight;
    std::memcpy(at_ + 2, &weight, kWeightBytes);
    at_ += kMaxGapWidth + kWeightBytes;
  }
  // Returns the byte after the row.
  std::uint8_t* finish() noexcept {
    const std::uint8_t* const postings = begin_ + kRowHeaderBytes;
    if (at_ == postings) return begin_;
    const std::size_t width = gap_width(gaps_);
    *begin_ = static_cast<std::uint8_t>(width | (counts_ ? kCountRow : 0));
    if (width == 2) return at_;
    // In place, front to back (each posting moves down); the value is read
    // whole before it is written, in sizes the compiler copies inline.
    std::uint8_t* out = begin_ + kRowHeaderBytes;
    if (counts_) {
      for (const std::uint8_t* in = postings; in != at_;
           in += 2 + kCountBytes, out += 1 + kCountBytes) {
        out[0] = in[0];
        out[1] = in[2];
      }
      return out;
    }
    for (const std::uint8_t* in = postings; in != at_; in += 2 + kWeightBytes) {
      std::uint8_t weight[kWeightBytes];
      std::memcpy(weight, in + 2, kWeightBytes);
      out[0] = in[0];
      std::memcpy(out + 1, weight, kWeightBytes);
      out += 1 + kWeightBytes;
    }
    return out;
  }

 private:
  // Rewrites the count postings so far as weight postings, from the last
  // (the entry before the one of `gap` being put) back: each moves to a
  // larger slot, past the ones still to read.
  void to_weights(std::uint32_t gap) {
    row_ = weights_.row(word_);
    counts_ = false;
    constexpr std::size_t kFrom = kMaxGapWidth + kCountBytes;
    constexpr std::size_t kTo = kMaxGapWidth + kWeightBytes;
    std::uint8_t* const postings = begin_ + kRowHeaderBytes;
    const std::size_t n = static_cast<std::size_t>(at_ - postings) / kFrom;
    std::uint32_t entry = entry_ - gap - 1;
    for (std::size_t i = n; i-- > 0;) {
      const std::uint8_t* in = postings + i * kFrom;
      const std::uint32_t previous_gap = read_gap<2>(in);
      const float weight = row_.weight(entry, in[2]);
      put_posting(postings + i * kTo, 2, previous_gap, weight);
      entry -= previous_gap + 1;
    }
    at_ = postings + n * kTo;
  }

  std::uint8_t* begin_;
  std::uint8_t* at_;
  SegmentWeights weights_;
  WordId word_;
  RowWeights row_;  // set when the first weight comes
  std::uint32_t entry_ = kRowStart;
  std::uint32_t gaps_ = 0;
  bool counts_ = true;
};

// Calls visit(relative_entry, PostingValue) for the postings of the row in
// [begin, end), in order.
template <class Visit>
inline void for_each_posting(const std::uint8_t* begin, const std::uint8_t* end,
                             const Visit& visit) {
  if (begin == end) return;
  const std::uint8_t header = *begin;
  const std::size_t width = header_width(header);
  const std::size_t stride = header_stride(header);
  const bool counts = header_counts(header);
  std::uint32_t entry = kRowStart;
  for (const std::uint8_t* at = begin + kRowHeaderBytes; at != end; at += stride) {
    entry += read_gap(at, width) + 1;
    visit(entry, counts ? PostingValue{at[width], 0.0f} : PostingValue{0, read_weight(at + width)});
  }
}

// So that a query's offset lookups stay few as the database grows, every
// kSegmentFanIn segments of one level are merged into one of the next, as
// long as the result spans at most kSegmentSpan ids (else the oldest of them
// that fit, if two do): a posting is copied once per level, and a query
// visits at most kSegmentFanIn - 1 segments of each level below the top,
// plus one per ~65,536 entries (8 for 100,000 images of 1000 words, ~30 for
// 1,000,000).
constexpr std::size_t kSegmentFanIn = 8;
constexpr unsigned kLoadedLevel = ~0u;

struct Segment {
  EntryId first_entry = 0;
  EntryId end_entry = 0;
  // Frozen from the tail: 0; merged from segments of level l: l + 1;
  // loaded (one per kSegmentSpan ids): kLoadedLevel, never merged.
  unsigned level = 0;
  std::vector<std::uint32_t> offsets;  // word_count + 1 byte offsets into `bytes`, by RowOrder
  SegmentBytes bytes;                  // the rows' postings (see above)
  std::size_t posting_count = 0;
  std::size_t dead_postings = 0;  // of removed entries, not yet dropped

  std::size_t postings() const noexcept { return posting_count; }
  const std::uint8_t* row_begin(std::uint32_t row) const noexcept {
    return bytes.data() + offsets[row];
  }
  const std::uint8_t* row_end(std::uint32_t row) const noexcept {
    return bytes.data() + offsets[row + 1];
  }
  std::size_t row_postings(std::uint32_t row) const noexcept {
    const std::uint32_t size = offsets[row + 1] - offsets[row];
    if (size == 0) return 0;
    return (size - kRowHeaderBytes) / header_stride(bytes.data()[offsets[row]]);
  }
};

}  // namespace detail

// The inverted index is a list of segments (oldest first) and a tail. New
// entries go to the tail; when it holds enough postings, or spans
// kSegmentSpan entries, it becomes a new segment (dropping removed entries),
// and a segment that removals have thinned out is compacted in place. Every
// entry lives in exactly one place: segments cover increasing entry ranges,
// the tail holds the entries from tail_first_entry on, each entry with its
// postings in increasing word order.
struct Database::Impl {
  Impl(Vocabulary vocabulary_in, DatabaseOptions options_in);
  // A database over caller-assigned word ids (Database::over_word_ids).
  Impl(Scoring scoring_in, DatabaseOptions options_in);

  // Sizes the tail and the rows for word ids below `word_capacity`; the
  // index must be empty of tail postings (a new or just frozen tail).
  void lay_out(std::size_t capacity);
  // The capacity and what follows from it (row order, key bits, segment size).
  void set_word_capacity(std::size_t capacity) noexcept;
  // Over word ids: makes room for ids below `needed` (at least doubling, so
  // that growth is amortised), freezing the tail and re-laying every
  // segment's rows for the new capacity.
  void grow_words(std::size_t needed);

  // Appends an entry whose arguments are already validated; exclusive lock held.
  EntryId append(const BowVector& bow, const FeatureVector& features);
  void store_label(EntryId entry, std::string label);
  // Turns the tail into a segment when it is full enough (or always).
  void freeze_tail_if_full();
  void freeze_tail();
  // The tail's live postings as a segment (null when it has none); the
  // index is unchanged.
  std::unique_ptr<detail::Segment> tail_as_segment() const;
  // Merges the newest segments while kSegmentFanIn of them share a level.
  void merge_segments_if_many();
  void merge_segments(std::size_t begin, std::size_t end);
  // Drops the postings of removed entries from a segment, or the whole
  // segment when none is left alive.
  void compact(std::size_t segment);
  // The segment that holds `entry`, or segments.size() when the tail does.
  std::size_t segment_of(EntryId entry) const noexcept;
  bool is_live(EntryId entry) const noexcept { return entry < alive.size() && alive[entry] != 0; }
  // Builds `forward` from the inverted index unless it is built: called by
  // queries (shared lock held), so that only databases queried in fast
  // mode pay its memory.
  void build_forward_index() const;
  // What turns counts into weights in a segment from `first_entry`.
  detail::SegmentWeights segment_weights(EntryId first_entry) const noexcept {
    return {over_word_ids ? nullptr : detail::word_weights(vocabulary),
            divisors.data() + first_entry};
  }

  Vocabulary vocabulary;  // empty over word ids
  DatabaseOptions options;
  Scoring scoring = Scoring::kL1;
  // The index's rows: the vocabulary's words, or the word-id capacity so far.
  std::size_t word_capacity = 0;
  bool over_word_ids = false;
  mutable detail::WriterPriorityMutex mutex;

  std::vector<std::unique_ptr<detail::Segment>> segments;

  // Tail: one list per 2^tail_list_shift groups (see kTailListShift); a
  // list has at most 2^high_bits rows.
  unsigned tail_list_shift = 0;
  unsigned high_bits = 0;
  detail::RowOrder row_order;
  std::uint32_t tail_list(WordId word) const noexcept {
    return detail::group_of(word) >> tail_list_shift;
  }
  // The first row of a list, and a word's row among its list's rows.
  std::uint32_t tail_list_start(std::uint32_t list) const noexcept {
    return row_order.group_start(list << tail_list_shift);
  }
  std::uint32_t tail_row(WordId word) const noexcept {
    return row_order.row(word) - tail_list_start(tail_list(word));
  }
  std::vector<detail::TailList> tail_lists;
  std::vector<std::uint8_t> first_block_logs;  // per list, see TailList
  detail::PostingArena arena;
  std::size_t tail_postings = 0;
  std::size_t tail_dead_postings = 0;
  std::size_t segment_postings = 0;  // the tail becomes a segment at this size
  EntryId tail_first_entry = 0;

  // Per entry, indexed by entry id (dead entries keep their place).
  std::vector<std::uint8_t> alive;
  std::vector<std::uint32_t> word_counts;  // postings the entry put in the index
  // The divisor of an entry in count form (CountForm, with counts up to
  // kMaxRowCount), whose segment postings may be counts; 0 for the others
  // (vectors not made by transform, databases over word ids, removed ones).
  std::vector<double> divisors;
  std::vector<detail::PackedFeatureVector> direct;  // empty without a direct index
  // Of a loaded database: the file's entries' direct index (theirs in
  // `direct` stay empty).
  detail::LoadedDirectIndex loaded_direct;
  std::vector<std::string> labels;  // empty until a label is set

  detail::CountForm count_form;  // of the entry being added

  // Each entry's BoW vector, for fast queries: built by the first one, then
  // kept up to date by add, remove and clear.
  mutable detail::ForwardIndex forward;
  mutable std::atomic<bool> forward_built{false};
  mutable std::mutex forward_mutex;

  std::size_t live_entries = 0;
  // Of every value added or loaded (removals do not narrow it): whether a
  // query's L1 terms may be summed as minimums.
  detail::ValueRange values;

  // The file last saved to or loaded from, and the changes since.
  mutable detail::DatabaseJournal journal;

  // The check of the file the database was loaded from, while it runs or
  // after it (null for a database not loaded, or cleared since). Once it
  // failed, every call throws its FileError (throw_if_damaged); calls that
  // read the index's bytes as a whole wait for it first (wait_for_file).
  std::unique_ptr<detail::BackgroundCheck> file_check;
  // Whether file_check's word counts and values are in word_counts and values.
  bool file_check_merged = true;
  void throw_if_damaged() const {
    if (file_check) file_check->throw_if_failed();
  }
  void wait_for_file() const {
    if (file_check) file_check->wait();
  }
  // Waits for file_check and takes what it found; exclusive lock held.
  void merge_file_check();
  // The range of the index's values, or false while it is not known (the
  // loaded file's are being checked).
  bool index_values(detail::ValueRange& range) const noexcept;
};

}  // namespace binbow
