// The state behind binbow::Database, shared by the index (database.cpp) and
// the .bbdb reader and writer (database_file.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <shared_mutex>
#include <string>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/database.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"

namespace binbow::detail {

// A posting of the tail tier: entry id and weight side by side, so that a
// short list (most are) is one cache line for both append and query.
struct TailPosting {
  EntryId entry;
  float weight;
};

// The tail postings of one word: where its block is in the arena, and how
// many postings it holds. Blocks grow by doubling from one posting, so the
// capacity is the smallest power of two ≥ size (at least that much: undoing
// an append may leave more room, never less).
struct TailList {
  std::uint32_t block = 0;  // a PostingArena address; meaningless while size is 0
  std::uint32_t size = 0;
};

// Storage of the tail tier's posting lists: blocks of 2^k postings carved
// from large chunks, with a free list per block size for the blocks that
// growing lists leave behind. Blocks are named by 32-bit addresses (chunk
// index, then position in the chunk) so a word's TailList is 8 bytes. The
// whole tier is dropped at once when it is merged, so there is no per-list
// malloc, free or header.
class PostingArena {
 public:
  static constexpr unsigned kChunkBits = 17;  // 2^17 postings: 1 MiB chunks

  PostingArena() noexcept { clear(); }
  // A block for `capacity` postings (a power of two).
  std::uint32_t allocate(std::uint32_t capacity);
  void release(std::uint32_t block, std::uint32_t capacity) noexcept;
  // Forgets every block but keeps the chunks of the usual size for reuse:
  // the tail fills again after each merge, and fresh memory costs a page
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

  std::vector<std::unique_ptr<TailPosting[]>> chunks_;
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

// A trivially copyable array in one malloc'd block, resized with realloc:
// the main tier grows in place this way (large blocks are remapped by the
// kernel, not copied) and no element is value-initialised for nothing.
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
    size_ = n;
  }
  void assign(const T* values, std::size_t n) {
    resize(n);
    if (n > 0) std::memcpy(data_, values, n * sizeof(T));
  }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

// One entry's FeatureVector, packed. Node ids are 32 bit. When every feature
// 0..n-1 sits under exactly one node (what transform produces), each feature
// just stores the position of its node, in 8 bits when there are at most 256
// nodes (about 1 byte per feature) or 16 bits; otherwise the end offset of
// every node's features and the feature indices follow, 16 bit when they fit
// (images have fewer than 65,536 features), else 32 bit.
class PackedFeatureVector {
 public:
  PackedFeatureVector() = default;
  explicit PackedFeatureVector(const FeatureVector& features);
  FeatureVector unpack() const;
  std::size_t memory_usage() const noexcept { return bytes_.capacity(); }

 private:
  enum class Layout : std::uint8_t { kPartition8, kPartition16, kRows16, kRows32 };
  std::uint32_t value(std::size_t byte_offset, std::size_t width) const noexcept;

  std::vector<std::uint8_t> bytes_;
  std::uint32_t node_count_ = 0;
  std::uint32_t feature_count_ = 0;
  Layout layout_ = Layout::kPartition8;
};

}  // namespace binbow::detail

namespace binbow {

// The inverted index has two tiers. The main tier is compressed rows by word
// (one offset per word, then all entry ids and all weights, exact size: 8
// bytes per posting). New entries go to the tail tier, one growable list per
// word, which is merged into the main tier (dropping removed entries) when it
// holds more than a quarter of all postings: each posting is copied a bounded
// number of times, the index stays compact, and every entry lives in exactly
// one tier (the tail holds the entries from tail_first_entry on), its
// postings in increasing word order.
struct Database::Impl {
  Impl(Vocabulary vocabulary_in, DatabaseOptions options_in);

  // Appends an entry whose arguments are already validated; exclusive lock held.
  EntryId append(const BowVector& bow, const FeatureVector& features);
  // Merges the tail into the main tier when worthwhile (or always).
  void merge_if_worthwhile();
  void merge();
  bool is_live(EntryId entry) const noexcept { return entry < alive.size() && alive[entry] != 0; }

  Vocabulary vocabulary;
  DatabaseOptions options;
  mutable std::shared_mutex mutex;

  // Main tier: postings of word w are [main_offsets[w], main_offsets[w + 1]).
  std::vector<std::uint32_t> main_offsets;  // word_count + 1, or empty
  detail::GrowableArray<EntryId> main_ids;
  detail::GrowableArray<float> main_weights;

  // Tail tier: one list per word, and one bit per word set while its list is
  // not empty (128 KiB for a million words: merges skip the words without
  // tail postings, and queries skip their lists, without touching them).
  std::vector<detail::TailList> tail_lists;
  std::vector<std::uint64_t> tail_words;
  detail::PostingArena arena;
  std::size_t tail_postings = 0;
  EntryId tail_first_entry = 0;

  // Per entry, indexed by entry id (dead entries keep their place).
  std::vector<std::uint8_t> alive;
  std::vector<std::uint32_t> word_counts;           // postings the entry put in the index
  std::vector<detail::PackedFeatureVector> direct;  // empty without a direct index
  std::vector<std::string> labels;                  // empty until a label is set

  std::size_t live_entries = 0;
  std::size_t postings = 0;       // in both tiers, dead ones included
  std::size_t dead_postings = 0;  // of removed entries, not yet dropped
};

}  // namespace binbow
