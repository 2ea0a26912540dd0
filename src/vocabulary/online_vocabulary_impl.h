// The state behind OnlineVocabulary, shared by its logic
// (online_vocabulary.cpp) and its file format (online_vocabulary_file.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

#include "binbow/online_vocabulary.h"

namespace binbow {

namespace detail {

inline constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;

// One randomised hierarchical clustering tree of words (Muja & Lowe). Node 0
// is the root. An inner node's children are contiguous; a leaf lists the
// slots of its words.
struct WordTree {
  struct Node {
    std::uint32_t first_child = 0;
    std::uint32_t child_count = 0;     // 0: a leaf
    std::vector<std::uint32_t> slots;  // a leaf's words
  };
  std::vector<Node> nodes;
  std::vector<std::uint8_t> centres;  // nodes × code_size; the root's is unused
  std::size_t built_words = 0;        // live words when last rebuilt
};

}  // namespace detail

// Live words occupy slots [0, word_count) of the per-slot arrays; purging a
// word moves the last slot into its place, so the descriptors stay contiguous
// (exact search and export read them as one matrix).
struct OnlineVocabulary::Impl {
  Impl(std::size_t code_size, OnlineVocabularyOptions options);

  std::size_t code_size;
  std::size_t bits;
  OnlineVocabularyOptions options;
  std::uint32_t new_word_bits;  // a word farther than this is a new word

  // Per slot.
  std::vector<std::uint8_t> descriptors;  // slots × code_size
  std::vector<OnlineWordInfo> info;
  std::vector<std::uint32_t> counter_block;  // index into counters, kNoSlot if none yet
  std::vector<std::uint32_t> leaves;         // slots × trees: the word's leaf in each tree
  // Live word id → slot. A map, not a table indexed by every id ever made:
  // memory follows the live words however many were purged.
  std::unordered_map<WordId, std::uint32_t> slot_of;

  // Majority counters of the words that have represented two descriptors or
  // more: per block, bits counters of ones, and the number of descriptors
  // they count (both halved when it reaches 255).
  std::vector<std::uint8_t> counters;  // blocks × bits
  std::vector<std::uint8_t> counter_totals;
  std::vector<std::uint32_t> free_blocks;

  std::vector<detail::WordTree> trees;
  // Words not yet old enough to be purged, oldest first.
  std::deque<WordId> purge_queue;

  std::uint32_t images = 0;
  WordId next_word_id = 0;
  std::size_t purged_words = 0;
  std::size_t tree_rebuilds = 0;
  // Random draws made so far: each split or rebuild seeds its generator from
  // (options.seed, this counter), so a restored state draws what it would have.
  std::uint64_t random_draws = 0;

  std::size_t word_count() const noexcept { return info.size(); }
  const std::uint8_t* slot_descriptor(std::uint32_t slot) const {
    return descriptors.data() + std::size_t{slot} * code_size;
  }
  std::uint32_t find_slot(WordId word) const {
    const auto it = slot_of.find(word);
    return it == slot_of.end() ? detail::kNoSlot : it->second;
  }

  // The slot of the nearest word (lowest id on ties among the words
  // compared) and its distance; detail::kNoSlot and kNoWord when there is no word.
  void nearest(const std::uint8_t* query, std::uint32_t& slot, std::uint32_t& distance) const;
  std::uint32_t create_word(const std::uint8_t* descriptor, std::uint32_t image);
  // Returns whether the word's descriptor changed.
  bool join_word(std::uint32_t slot, const std::uint8_t* descriptor, std::uint32_t image);
  void purge(std::uint32_t slot);
  void purge_expired(std::vector<WordId>& purged);
  // Rebuilds every tree grown to twice its size at the last build.
  void rebuild_grown_trees();
  void rebuild_tree(std::size_t tree);
  void insert_into_tree(std::size_t tree, std::uint32_t slot);
  // Moves a word whose descriptor changed to the leaf its descriptor now reaches.
  void reinsert_into_tree(std::size_t tree, std::uint32_t slot);
  // Splits a leaf holding more than leaf_size words, and its children as long
  // as they do too.
  void split_leaf(std::size_t tree, std::uint32_t leaf);
  // After loading: the purge queue from the words' counts.
  void restore_purge_queue();
  // After loading a file with trees (.bbov version 2): the trees of its
  // sections 6..9 (`data` and `size` start at section 6), the words loaded
  // already. Problems go to `fail`, which throws.
  void read_trees(const std::uint8_t* const* data, const std::size_t* size,
                  const std::function<void(const std::string&)>& fail);
  // After loading a file without trees (.bbov version 1): the trees rebuilt
  // from the words.
  void rebuild_trees_after_load();
  std::size_t memory_usage() const;
};

}  // namespace binbow
