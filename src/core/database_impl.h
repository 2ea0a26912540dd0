// The state behind binbow::Database, shared by the index (database.cpp) and
// the .bbdb reader and writer (database_file.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <shared_mutex>
#include <string>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/database.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"

namespace binbow::detail {

// Storage of the tail tier's posting lists: blocks of 2^k postings (8 bytes
// each) carved from large chunks, with a free list per block size for the
// blocks that growing lists leave behind. The whole tier is dropped at once
// when it is merged, so there is no per-list malloc, free or header.
class PostingArena {
 public:
  // A block for `capacity` postings (a power of two).
  unsigned char* allocate(std::uint32_t capacity);
  void release(unsigned char* block, std::uint32_t capacity) noexcept;
  void clear() noexcept;
  std::size_t memory_usage() const noexcept { return chunk_bytes_; }

 private:
  static constexpr std::size_t kChunkPostings = std::size_t{1} << 17;  // 1 MiB
  std::vector<std::unique_ptr<unsigned char[]>> chunks_;
  unsigned char* free_lists_[32] = {};
  unsigned char* bump_ = nullptr;
  std::size_t bump_left_ = 0;  // in postings (8 bytes)
  std::size_t chunk_bytes_ = 0;
};

// The tail postings of one word: entry ids (strictly increasing) and their
// weights, as two arrays in one arena block, so a query streams through both.
class PostingList {
 public:
  std::uint32_t size() const noexcept { return size_; }
  const EntryId* ids() const noexcept { return reinterpret_cast<const EntryId*>(block_); }
  const float* weights() const noexcept {
    return reinterpret_cast<const float*>(ids() + capacity_);
  }

  void push_back(EntryId entry, float weight, PostingArena& arena);
  void pop_back() noexcept { --size_; }
  // Hints the cache about where the next push_back writes.
  void prefetch_end() const noexcept {
    __builtin_prefetch(ids() + size_);
    __builtin_prefetch(weights() + size_);
  }

 private:
  unsigned char* block_ = nullptr;  // capacity_ ids, then capacity_ floats
  std::uint32_t size_ = 0;
  std::uint32_t capacity_ = 0;
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
// one tier, its postings in increasing word order.
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
  std::vector<std::uint32_t> main_offsets;  // word_count + 1
  std::vector<EntryId> main_ids;
  std::vector<float> main_weights;

  // Tail tier: word → slot + 1 (0: no tail postings).
  std::vector<std::uint32_t> slot_of_word;
  std::vector<detail::PostingList> lists;
  detail::PostingArena arena;
  std::size_t tail_postings = 0;

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
