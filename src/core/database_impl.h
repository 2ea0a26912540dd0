// The state behind binbow::Database, shared by the index (database.cpp) and
// the .bbdb reader and writer (database_file.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <shared_mutex>
#include <string>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/database.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"

namespace binbow::detail {

// The postings of one word: entry ids (strictly increasing) and their weights,
// as two arrays in one allocation, so a query streams through both. 16 bytes
// of bookkeeping per word in use; growth by 1.5× keeps slack small.
class PostingList {
 public:
  PostingList() = default;
  PostingList(const PostingList&) = delete;
  PostingList& operator=(const PostingList&) = delete;
  PostingList(PostingList&& other) noexcept;
  PostingList& operator=(PostingList&& other) noexcept;
  ~PostingList();

  std::uint32_t size() const noexcept { return size_; }
  const EntryId* ids() const noexcept { return ids_; }
  const float* weights() const noexcept { return reinterpret_cast<const float*>(ids_ + capacity_); }

  void push_back(EntryId entry, float weight);
  void pop_back() noexcept { --size_; }
  // Hints the cache about where the next push_back writes.
  void prefetch_end() const noexcept {
    __builtin_prefetch(ids_ + size_);
    __builtin_prefetch(weights() + size_);
  }
  std::size_t memory_usage() const noexcept;

 private:
  void reallocate(std::uint32_t capacity);
  float* mutable_weights() noexcept { return reinterpret_cast<float*>(ids_ + capacity_); }

  EntryId* ids_ = nullptr;  // capacity_ ids, then capacity_ floats
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
// holds more than an eighth of all postings: each posting is copied a bounded
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
