#include "core/forward_index.h"

#include "core/count_form.h"

namespace binbow::detail {

namespace {

// A step of up to 15 bits takes one code, a larger one three.
constexpr std::uint32_t kShortStep = 0x7FFF;

std::size_t step_codes(std::uint32_t step) noexcept {
  return step <= kShortStep ? 1 : 3;
}

// Writes a word's step code (with `flag`); returns the code after it.
std::uint16_t* put_step(std::uint16_t* out, std::uint32_t step, std::uint16_t flag) noexcept {
  if (step <= kShortStep) {
    *out = static_cast<std::uint16_t>(step | flag);
    return out + 1;
  }
  out[0] = flag;
  out[1] = static_cast<std::uint16_t>(step & 0xFFFF);
  out[2] = static_cast<std::uint16_t>(step >> 16);
  return out + 3;
}

template <typename T>
std::uint16_t* put_raw(std::uint16_t* out, T value) noexcept {
  std::memcpy(out, &value, sizeof(T));
  return out + sizeof(T) / 2;
}

}  // namespace

ForwardIndex::ForwardIndex(const Vocabulary* vocabulary, Scoring scoring)
    : has_vocabulary_(vocabulary != nullptr), scoring_(scoring) {
  if (vocabulary != nullptr) vocabulary_ = *vocabulary;
}

void ForwardIndex::append(Span<BowEntry> words) {
  entries_.push_back(encode(words, find_count_form(words)));
}

void ForwardIndex::append(Span<BowEntry> words, const CountForm* form) {
  entries_.push_back(encode(words, form));
}

void ForwardIndex::assign(EntryId entry, Span<BowEntry> words) {
  entries_[entry] = encode(words, find_count_form(words));
}

std::size_t ForwardIndex::memory_usage() const noexcept {
  std::size_t bytes = entries_.capacity() * sizeof(entries_[0]);
  for (const auto& codes : entries_) bytes += codes.capacity() * sizeof(std::uint16_t);
  return bytes;
}

const CountForm* ForwardIndex::find_count_form(Span<BowEntry> words) {
  return has_vocabulary_ && form_.find(vocabulary_, scoring_, words) ? &form_ : nullptr;
}

// Sized first, then written once: an add's entry costs one allocation and
// one pass over its words.
std::vector<std::uint16_t> ForwardIndex::encode(Span<BowEntry> words, const CountForm* form) {
  const std::size_t n = words.size();
  if (n == 0) return {};
  const std::uint32_t* const counts = form != nullptr ? form->counts().data() : nullptr;
  std::size_t size = form != nullptr ? kCountsHeader : kFloatsHeader + 2 * n;
  std::uint32_t previous = ~std::uint32_t{0};
  for (std::size_t i = 0; i < n; ++i) {
    size += step_codes(words[i].word - previous);
    previous = words[i].word;
    if (counts != nullptr) size += counts[i] > 1 ? 1 : 0;
  }
  std::vector<std::uint16_t> codes(size);
  std::uint16_t* out = codes.data();
  previous = ~std::uint32_t{0};
  if (counts != nullptr) {
    // The compact form: the divisor and the counts above 1.
    *out++ = kCounts;
    out = put_raw(out, form->divisor());
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t count = counts[i];
      out = put_step(out, words[i].word - previous, count > 1 ? kMany : 0);
      previous = words[i].word;
      if (count > 1) *out++ = static_cast<std::uint16_t>(count);
    }
    return codes;
  }
  *out++ = kFloats;
  out = put_raw(out, static_cast<std::uint32_t>(n));
  for (std::size_t i = 0; i < n; ++i) {
    out = put_step(out, words[i].word - previous, 0);
    previous = words[i].word;
  }
  for (std::size_t i = 0; i < n; ++i) out = put_raw(out, words[i].value);
  return codes;
}

}  // namespace binbow::detail
