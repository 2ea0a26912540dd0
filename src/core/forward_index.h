// Every entry's BoW vector, as the inverted index holds it (the same words
// and weights, bit for bit): what a fast query scores its candidates with,
// one sequential read per candidate instead of a lookup in each query word's
// posting list.
//
// Compact, so that fast queries do not double the database's memory: word
// ids are steps from the previous word in 16 bits (2 bytes per word instead
// of 4). The weight of an entry made by Vocabulary::transform is
// float(word_weight(w) * count / divisor), with one divisor per entry (the
// norm of the weighted counts): such an entry keeps its divisor and the
// counts above 1 (about 2 bytes per word in all, instead of 8), and its
// weights are computed again, bit for bit, when a query needs them. An entry
// is kept in that form only when every weight computed so equals the given
// one to the last bit; other entries (any database over word ids, vectors
// not made by transform) keep their floats (about 6 bytes per word).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/span.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"
#include "core/count_form.h"

namespace binbow::detail {

class ForwardIndex {
 public:
  ForwardIndex() = default;
  // `vocabulary` (null over word ids) gives the word weights that compact
  // entries are computed from, as transform with `scoring` computes them.
  ForwardIndex(const Vocabulary* vocabulary, Scoring scoring);

  // Appends the next entry's words (sorted by increasing word id).
  void append(Span<BowEntry> words);
  // The same, with what the caller found already: `form` is the words'
  // count form (CountForm::find was true for this index's vocabulary and
  // scoring), or null when they have none, so that an add does not look up
  // every word's weight a second time.
  void append(Span<BowEntry> words, const CountForm* form);
  // Makes room for `entries` entries; new ones have no words.
  void resize(std::size_t entries) { entries_.resize(entries); }
  // Sets the words of an entry (below size()).
  void assign(EntryId entry, Span<BowEntry> words);
  void drop(EntryId entry) { std::vector<std::uint16_t>().swap(entries_[entry]); }
  void truncate(std::size_t entries) {
    if (entries_.size() > entries) entries_.resize(entries);
  }
  void clear() { std::vector<std::vector<std::uint16_t>>().swap(entries_); }
  std::size_t size() const noexcept { return entries_.size(); }
  std::size_t memory_usage() const noexcept;

  // The weight of a query word, as compact entries compute theirs from it:
  // its vocabulary weight (0 over word ids or beyond the vocabulary, where
  // no entry is compact).
  double word_weight(WordId word) const {
    return has_vocabulary_ && word < vocabulary_.word_count()
               ? static_cast<double>(vocabulary_.word_weight(word))
               : 0.0;
  }

  // Starts fetching an entry's first codes (the rest follow in order).
  void prefetch(EntryId entry) const noexcept {
    const auto* codes = reinterpret_cast<const char*>(entries_[entry].data());
    for (int line = 0; line < 4; ++line) __builtin_prefetch(codes + 64 * line);
  }

  // Calls take(q, weight) for every word of `entry` that the query holds,
  // in increasing word order, with its weight in the entry: q is
  // position(word), which is `absent` for the words the query lacks, and
  // `query_weights[q]` is word_weight() of the query's word q. `hits` is
  // the caller's buffer. The words are looked up first, without branches,
  // then the weights of the shared ones computed: about half of a
  // candidate's words are shared, so a branch per word would mispredict
  // often.
  template <class Position, class Take>
  [[gnu::always_inline]] void for_each_shared(EntryId entry, const Position& position,
                                              std::uint32_t absent, const double* query_weights,
                                              std::vector<std::uint32_t>& hits, Take&& take) const {
    const std::vector<std::uint16_t>& codes = entries_[entry];
    if (codes.empty()) return;
    if (hits.size() < 2 * codes.size()) hits.resize(2 * codes.size());
    std::uint32_t* const found = hits.data();
    if (codes[0] == kCounts) {
      double divisor;
      std::memcpy(&divisor, codes.data() + 1, sizeof divisor);
      const double inverse = inverse_divisor(divisor);
      const std::uint32_t* end = look_up<true>(
          codes.data() + kCountsHeader, codes.data() + codes.size(), position, absent, found);
      for (const std::uint32_t* hit = found; hit < end; hit += 2)
        take(hit[0], count_weight(query_weights[hit[0]], hit[1], inverse, &divisor));
    } else {
      std::uint32_t words;
      std::memcpy(&words, codes.data() + 1, sizeof words);
      const std::uint16_t* floats = codes.data() + codes.size() - 2 * std::size_t{words};
      const std::uint32_t* end =
          look_up<false>(codes.data() + kFloatsHeader, floats, position, absent, found);
      for (const std::uint32_t* hit = found; hit < end; hit += 2) {
        float weight;
        std::memcpy(&weight, floats + 2 * std::size_t{hit[1]}, sizeof weight);
        take(hit[0], weight);
      }
    }
  }

 private:
  // An entry's codes: kCounts, the divisor (a double, 4 codes), then per
  // word its step and, when the step code has kMany, its count; or kFloats,
  // the word count (32 bits, 2 codes), per word its step, then the weights
  // (2 codes each). A step is the word's id minus the previous word's (the
  // first word's id plus one) in the low 15 bits, or 0 there and the step in
  // the next two codes (low half first) when it does not fit.
  static constexpr std::uint16_t kCounts = 1;
  static constexpr std::uint16_t kFloats = 2;
  static constexpr std::size_t kCountsHeader = 5;
  static constexpr std::size_t kFloatsHeader = 3;
  static constexpr std::uint16_t kMany = 0x8000;
  static constexpr std::uint32_t kStepMask = 0x7FFF;

  // Writes (q, count) with kCounts, or (q, word index) without, for each
  // word between `code` and `end` that the query holds; returns the end of
  // what it wrote.
  template <bool kWithCounts, class Position>
  [[gnu::always_inline]] static std::uint32_t* look_up(const std::uint16_t* code,
                                                       const std::uint16_t* end,
                                                       const Position& position,
                                                       std::uint32_t absent, std::uint32_t* out) {
    std::uint32_t word = ~std::uint32_t{0};
    std::uint32_t index = 0;
    while (code < end) {
      const std::uint32_t step_code = *code++;
      std::uint32_t step = step_code & kStepMask;
      if (step == 0) {
        step = code[0] | std::uint32_t{code[1]} << 16;
        code += 2;
      }
      word += step;
      std::uint32_t aux = index++;
      if constexpr (kWithCounts) {
        // Without a branch (few words have a count): the next code, or the
        // step's own code when it was the last, masked out unless kMany.
        const std::uint32_t many = step_code >> 15;
        const std::uint32_t next = *(code - (code == end ? 1 : 0));
        aux = 1 + ((next - 1) & (0u - many));
        code += many;
      }
      const std::uint32_t q = position(word);
      out[0] = q;
      out[1] = aux;
      out += q != absent ? 2 : 0;
    }
    return out;
  }

  // An entry's codes, allocated at their exact size: in the compact form of
  // `form` (the words' count form), or with their floats when it is null.
  static std::vector<std::uint16_t> encode(Span<BowEntry> words, const CountForm* form);
  // `words`' count form if they have one (in form_'s buffers), else null.
  const CountForm* find_count_form(Span<BowEntry> words);

  Vocabulary vocabulary_;
  bool has_vocabulary_ = false;
  Scoring scoring_ = Scoring::kL1;
  std::vector<std::vector<std::uint16_t>> entries_;
  CountForm form_;  // find_count_form's buffers
};

}  // namespace binbow::detail
