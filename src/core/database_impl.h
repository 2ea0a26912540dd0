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
  // Replaces the content with `count` postings, with no spare capacity.
  void assign(const EntryId* entries, const float* weights, std::uint32_t count);
  // Drops the postings of entries for which alive[entry] is 0; returns how many.
  std::size_t erase_dead(const std::vector<std::uint8_t>& alive);
  std::size_t memory_usage() const noexcept;

 private:
  void reallocate(std::uint32_t capacity);
  float* mutable_weights() noexcept { return reinterpret_cast<float*>(ids_ + capacity_); }

  EntryId* ids_ = nullptr;  // capacity_ ids, then capacity_ floats
  std::uint32_t size_ = 0;
  std::uint32_t capacity_ = 0;
};

// One entry's FeatureVector, packed: node ids (32 bit), then the end offset
// of every node's features and the feature indices, both 16 bit when every
// value fits (images have fewer than 65,536 features), else 32 bit.
class PackedFeatureVector {
 public:
  PackedFeatureVector() = default;
  explicit PackedFeatureVector(const FeatureVector& features);
  FeatureVector unpack() const;
  std::size_t memory_usage() const noexcept { return bytes_.capacity(); }

 private:
  std::uint32_t value(std::size_t byte_offset) const noexcept;

  std::vector<std::uint8_t> bytes_;
  std::uint32_t node_count_ = 0;
  std::uint32_t feature_count_ = 0;
  bool wide_ = false;
};

}  // namespace binbow::detail

namespace binbow {

struct Database::Impl {
  Impl(Vocabulary vocabulary_in, DatabaseOptions options_in);

  // Appends an entry whose arguments are already validated; exclusive lock held.
  EntryId append(const BowVector& bow, const FeatureVector& features);
  // Drops dead postings once they are a large share of the index.
  void compact_if_worthwhile();
  void compact();
  bool is_live(EntryId entry) const noexcept { return entry < alive.size() && alive[entry] != 0; }

  Vocabulary vocabulary;
  DatabaseOptions options;
  mutable std::shared_mutex mutex;

  // Inverted index: word → slot + 1 (0: the word has no postings yet).
  std::vector<std::uint32_t> slot_of_word;
  std::vector<detail::PostingList> lists;

  // Per entry, indexed by entry id (dead entries keep their place).
  std::vector<std::uint8_t> alive;
  std::vector<std::uint32_t> word_counts;           // postings the entry put in the index
  std::vector<detail::PackedFeatureVector> direct;  // empty without a direct index
  std::vector<std::string> labels;                  // empty until a label is set

  std::size_t live_entries = 0;
  std::size_t postings = 0;       // in the lists, dead ones included
  std::size_t dead_postings = 0;  // of removed entries, not yet dropped
};

}  // namespace binbow
