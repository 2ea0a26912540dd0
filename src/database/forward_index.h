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

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/span.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"
#include "database/count_form.h"
#include "database/query_word_set.h"

namespace binbow::detail {

// For tests: while set, ForwardIndex looks words up with its portable code,
// as on CPUs without AVX2, so that tests compare it with the vector code.
std::atomic<bool>& portable_forward_lookups();

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

  // Starts fetching where an entry's codes are, for prefetch() a step later.
  void prefetch_location(EntryId entry) const noexcept { __builtin_prefetch(&entries_[entry]); }
  // Starts fetching all of an entry's codes (about 30 cache lines for an
  // ORB-1000 image), so that its look-up does not wait for them.
  void prefetch(EntryId entry) const noexcept {
    const std::vector<std::uint16_t>& codes = entries_[entry];
    const auto* bytes = reinterpret_cast<const char*>(codes.data());
    const std::size_t size = codes.size() * sizeof(std::uint16_t);
    for (std::size_t line = 0; line < size; line += 64) __builtin_prefetch(bytes + line);
  }

  // Calls take(q, weight) for every word of `entry` that the query holds,
  // in increasing word order, with its weight in the entry: q is
  // query.position(word), and `query_weights[q]` is word_weight() of the
  // query's word q. `hits` is the caller's buffer. The words are looked up
  // first, out of line (8 at a time with AVX2 where the CPU has it), then
  // the weights of the shared ones computed: about a fifth to a half of a
  // candidate's words are shared, so a branch per word would mispredict
  // often.
  template <class Take>
  [[gnu::always_inline]] void for_each_shared(EntryId entry, const QueryWordSet& query,
                                              const double* query_weights,
                                              std::vector<std::uint32_t>& hits, Take&& take) const {
    const std::uint16_t* const codes = entries_[entry].data();
    if (entries_[entry].empty()) return;
    const std::uint32_t words = read<std::uint32_t>(codes + kWordsAt);
    const std::uint32_t long_steps = read<std::uint32_t>(codes + kLongStepsAt);
    const std::size_t room = std::size_t{words} + kLookUpSlack;
    if (hits.size() < 2 * room) hits.resize(2 * room);
    std::uint32_t* const positions = hits.data();
    std::uint32_t* const details = positions + room;
    const std::size_t found = look_up(codes, query, positions, details);
    if (codes[0] == kCounts) {
      const double divisor = read<double>(codes + kDivisorAt);
      const double inverse = inverse_divisor(divisor);
      const std::uint16_t* const counts =
          codes + kCountsHeader + words + 2 * std::size_t{long_steps};
      for (std::size_t k = 0; k < found; ++k) {
        const std::uint32_t q = positions[k];
        take(q, count_weight(query_weights[q], counts[details[k]], divisor, inverse));
      }
    } else {
      const std::uint16_t* const floats =
          codes + kFloatsHeader + words + 2 * std::size_t{long_steps};
      for (std::size_t k = 0; k < found; ++k)
        take(positions[k], read<float>(floats + 2 * std::size_t{details[k]}));
    }
  }

 private:
  // An entry's codes: its form (kCounts or kFloats), its word count and its
  // count of long steps (32 bits each, 2 codes), for kCounts the divisor (a
  // double, 4 codes); then one code per word: its step (the word's id minus
  // the previous word's, the first word's id plus one) in the low 15 bits,
  // or 0 there for a step beyond them, and kMany in a compact entry when the
  // word's count is above 1; then the long steps in order (32 bits each);
  // then a compact entry's counts (1 first, then the count of each word with
  // kMany, in order) or the other's weights (floats, 2 codes each). One
  // code per word, with no count or long step between them, lets vector code
  // decode 8 words at once with a prefix sum.
  static constexpr std::uint16_t kCounts = 1;
  static constexpr std::uint16_t kFloats = 2;
  static constexpr std::size_t kWordsAt = 1;
  static constexpr std::size_t kLongStepsAt = 3;
  static constexpr std::size_t kDivisorAt = 5;
  static constexpr std::size_t kCountsHeader = 9;
  static constexpr std::size_t kFloatsHeader = 5;
  static constexpr std::uint16_t kMany = 0x8000;
  // What look_up may write past the words it finds.
  static constexpr std::size_t kLookUpSlack = 8;

  template <typename T>
  static T read(const std::uint16_t* codes) noexcept {
    T value;
    std::memcpy(&value, codes, sizeof value);
    return value;
  }

  // For each word of the entry that the query holds, in order, writes its
  // position in the query and (compact entries) the index of its count, 0
  // for a count of 1, or (others) the word's index; returns how many.
  static std::size_t look_up(const std::uint16_t* codes, const QueryWordSet& query,
                             std::uint32_t* positions, std::uint32_t* details);

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
