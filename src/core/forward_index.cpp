#include "core/forward_index.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace binbow::detail {

namespace {

// Appends a word's step code (with `flag`) after `previous`.
void push_step(std::vector<std::uint16_t>& codes, std::uint32_t& previous, WordId word,
               std::uint16_t flag) {
  const std::uint32_t step = word - previous;
  previous = word;
  if (step <= 0x7FFF) {
    codes.push_back(static_cast<std::uint16_t>(step | flag));
  } else {
    codes.push_back(flag);
    codes.push_back(static_cast<std::uint16_t>(step & 0xFFFF));
    codes.push_back(static_cast<std::uint16_t>(step >> 16));
  }
}

template <typename T>
void push_raw(std::vector<std::uint16_t>& codes, T value) {
  std::uint16_t halves[sizeof(T) / 2];
  std::memcpy(halves, &value, sizeof(T));
  codes.insert(codes.end(), halves, halves + sizeof(T) / 2);
}

bool same_bits(float a, float b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

}  // namespace

ForwardIndex::ForwardIndex(const Vocabulary* vocabulary, Scoring scoring)
    : has_vocabulary_(vocabulary != nullptr), scoring_(scoring) {
  if (vocabulary != nullptr) vocabulary_ = *vocabulary;
}

void ForwardIndex::append(Span<BowEntry> words) {
  std::vector<std::uint16_t> codes;
  encode(words, codes);
  entries_.push_back(std::move(codes));
}

void ForwardIndex::assign(EntryId entry, Span<BowEntry> words) {
  std::vector<std::uint16_t> codes;
  encode(words, codes);
  entries_[entry] = std::move(codes);
}

std::size_t ForwardIndex::memory_usage() const noexcept {
  std::size_t bytes = entries_.capacity() * sizeof(entries_[0]);
  for (const auto& codes : entries_) bytes += codes.capacity() * sizeof(std::uint16_t);
  return bytes;
}

void ForwardIndex::encode(Span<BowEntry> words, std::vector<std::uint16_t>& codes) const {
  if (words.empty()) return;
  if (!encode_counts(words, codes)) encode_floats(words, codes);
  codes.shrink_to_fit();
}

void ForwardIndex::encode_floats(Span<BowEntry> words, std::vector<std::uint16_t>& codes) {
  codes.clear();
  codes.reserve(kFloatsHeader + 4 * words.size());
  codes.push_back(kFloats);
  push_raw(codes, static_cast<std::uint32_t>(words.size()));
  std::uint32_t previous = ~std::uint32_t{0};
  for (const BowEntry& e : words) push_step(codes, previous, e.word, 0);
  for (const BowEntry& e : words) push_raw(codes, e.value);
}

// Transform gives word w the weight float(weight(w) * count / divisor), in
// doubles, where the divisor is the L1 norm of the weight(w) * count (L2
// norm for L2; the word count, or 1, for the dot product): the counts are
// the weights over the smallest, rounded, and the form is kept only if it
// gives back every weight exactly.
bool ForwardIndex::encode_counts(Span<BowEntry> words, std::vector<std::uint16_t>& codes) const {
  if (!has_vocabulary_) return false;
  const std::size_t n = words.size();
  std::vector<double> weights(n);
  double smallest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    weights[i] = word_weight(words[i].word);
    if (!(weights[i] > 0) || !(words[i].value > 0)) return false;
    smallest = std::min(smallest, static_cast<double>(words[i].value) / weights[i]);
  }
  std::vector<std::uint16_t> counts(n);
  std::vector<double> raw(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double count = std::round(static_cast<double>(words[i].value) / weights[i] / smallest);
    if (!(count >= 1 && count <= 0xFFFF)) return false;
    counts[i] = static_cast<std::uint16_t>(count);
    raw[i] = weights[i] * count;
  }
  double divisors[2] = {0, 1};
  if (scoring_ == Scoring::kL2) {
    for (double v : raw) divisors[0] += v * v;
    divisors[0] = std::sqrt(divisors[0]);
  } else if (scoring_ == Scoring::kDotProduct) {
    divisors[0] = static_cast<double>(n);
  } else {
    for (double v : raw) divisors[0] += std::fabs(v);
  }
  for (double divisor : divisors) {
    bool exact = true;
    for (std::size_t i = 0; i < n && exact; ++i)
      exact = same_bits(static_cast<float>(weights[i] * static_cast<double>(counts[i]) / divisor),
                        words[i].value);
    if (!exact) continue;
    codes.clear();
    codes.reserve(kCountsHeader + n + n / 8 + 8);
    codes.push_back(kCounts);
    push_raw(codes, divisor);
    std::uint32_t previous = ~std::uint32_t{0};
    for (std::size_t i = 0; i < n; ++i) {
      push_step(codes, previous, words[i].word, counts[i] > 1 ? kMany : 0);
      if (counts[i] > 1) codes.push_back(counts[i]);
    }
    return true;
  }
  return false;
}

}  // namespace binbow::detail
