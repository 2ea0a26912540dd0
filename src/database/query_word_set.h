// A query's words as a bitmap over word ids, for fast mode's rescoring
// (ForwardIndex::for_each_shared): a word's position in the query in a few
// instructions. One 64-bit record per 32 word ids holds their bits (low
// half) and the number of the query's words below them (high half), so that
// a lookup reads one cache line (8 bytes per 32 ids: 135 KiB for 540k words,
// in the core's cache); vector code reads the bits of 8 words, then the
// ranks of the words found only.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/span.h"
#include "binbow/types.h"

namespace binbow::detail {

class QueryWordSet {
 public:
  // Words sorted by increasing id, as a BowVector holds them.
  void assign(Span<BowEntry> words) {
    const std::size_t blocks = words.empty() ? 1 : words[words.size() - 1].word / 32 + 1;
    records_.assign(blocks, 0);
    for (const BowEntry& e : words) records_[e.word / 32] |= std::uint64_t{1} << (e.word % 32);
    std::uint32_t rank = 0;
    for (std::uint64_t& record : records_) {
      const auto bits = static_cast<std::uint32_t>(record);
      record |= std::uint64_t{rank} << 32;
      rank += popcount(bits);
    }
    absent_ = rank;
  }

  // Inline: without -mpopcnt, __builtin_popcount is a library call. With
  // kInstruction, the caller is compiled for the popcnt instruction, where
  // the builtin is that instruction.
  template <bool kInstruction = false>
  [[gnu::always_inline]] static std::uint32_t popcount(std::uint32_t x) noexcept {
#if !defined(__POPCNT__)
    if constexpr (!kInstruction) {
      x -= (x >> 1) & 0x55555555u;
      x = (x & 0x33333333u) + ((x >> 2) & 0x33333333u);
      x = (x + (x >> 4)) & 0x0F0F0F0Fu;
      return (x * 0x01010101u) >> 24;
    }
#endif
    return static_cast<std::uint32_t>(__builtin_popcount(x));
  }

  // The word's position in the query, or absent() if the query lacks it.
  // Without branches (a mask, not a conditional, which compilers turn into
  // a branch): about half the words looked up are the query's.
  template <bool kPopcnt = false>
  [[gnu::always_inline]] std::uint32_t position(WordId word) const noexcept {
    const std::size_t block = word / 32;
    const std::size_t last = records_.size() - 1;
    const std::uint64_t record = records_[std::min(block, last)];
    const auto bits = block <= last ? static_cast<std::uint32_t>(record) : 0u;
    const std::uint32_t below = (std::uint32_t{1} << (word % 32)) - 1;
    const auto rank = static_cast<std::uint32_t>(record >> 32) + popcount<kPopcnt>(bits & below);
    const std::uint32_t present = (bits >> (word % 32)) & 1;
    return absent_ + ((rank - absent_) & (0u - present));
  }

  // The position of a word the query holds (a word it lacks gets a wrong
  // one): for vector code that tested the word's bit already.
  template <bool kPopcnt = false>
  [[gnu::always_inline]] std::uint32_t position_of_held(WordId word) const noexcept {
    const std::uint64_t record = records_[word / 32];
    const std::uint32_t below = (std::uint32_t{1} << (word % 32)) - 1;
    return static_cast<std::uint32_t>(record >> 32) +
           popcount<kPopcnt>(static_cast<std::uint32_t>(record) & below);
  }

  // The query's size: the position of the words it lacks.
  std::uint32_t absent() const noexcept {
    return absent_;
  }
  const std::uint64_t* records() const noexcept {
    return records_.data();
  }
  std::size_t blocks() const noexcept {
    return records_.size();
  }

 private:
  std::vector<std::uint64_t> records_{0};
  std::uint32_t absent_ = 0;
};

}  // namespace binbow::detail
