#include "core/forward_index.h"

#include "core/count_form.h"

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

// The compact form of CountForm: its divisor and the counts above 1.
bool ForwardIndex::encode_counts(Span<BowEntry> words, std::vector<std::uint16_t>& codes) const {
  if (!has_vocabulary_) return false;
  CountForm form;
  if (!form.find(vocabulary_, scoring_, words)) return false;
  const std::size_t n = words.size();
  codes.clear();
  codes.reserve(kCountsHeader + n + n / 8 + 8);
  codes.push_back(kCounts);
  push_raw(codes, form.divisor());
  std::uint32_t previous = ~std::uint32_t{0};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t count = form.counts()[i];
    push_step(codes, previous, words[i].word, count > 1 ? kMany : 0);
    if (count > 1) codes.push_back(static_cast<std::uint16_t>(count));
  }
  return true;
}

}  // namespace binbow::detail
