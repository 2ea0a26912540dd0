// Every entry's BoW vector, as the inverted index holds it (the same words
// and weights, bit for bit): what a fast query scores its candidates with,
// one sequential read of 8 bytes per word per candidate, instead of a
// lookup in each query word's posting list.
#pragma once

#include <cstddef>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/span.h"
#include "binbow/types.h"

namespace binbow::detail {

class ForwardIndex {
 public:
  // Appends the next entry's words (sorted by increasing word id).
  void append(Span<BowEntry> words) { entries_.emplace_back(words.begin(), words.end()); }
  // Appends an entry of `count` words, which add_word then gives in
  // increasing word order.
  void append_empty(std::size_t count) { entries_.emplace_back().reserve(count); }
  void add_word(EntryId entry, WordId word, float weight) {
    entries_[entry].push_back({word, weight});
  }

  void drop(EntryId entry) { std::vector<BowEntry>().swap(entries_[entry]); }
  void truncate(std::size_t entries) {
    if (entries_.size() > entries) entries_.resize(entries);
  }
  void clear() { std::vector<std::vector<BowEntry>>().swap(entries_); }
  std::size_t memory_usage() const noexcept {
    std::size_t bytes = entries_.capacity() * sizeof(entries_[0]);
    for (const auto& words : entries_) bytes += words.capacity() * sizeof(BowEntry);
    return bytes;
  }

  Span<BowEntry> words(EntryId entry) const noexcept {
    return {entries_[entry].data(), entries_[entry].size()};
  }

 private:
  std::vector<std::vector<BowEntry>> entries_;
};

}  // namespace binbow::detail
