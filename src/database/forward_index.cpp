#include "database/forward_index.h"

#include <array>

#include "database/count_form.h"

#if defined(BINBOW_X86_DISPATCH)
#include <immintrin.h>
#endif

namespace binbow::detail {

namespace {

// A step of 1 to 15 bits is kept in its word's code, others (0 only for a
// word id of 2^32 - 1, the first) among the long steps.
constexpr std::uint32_t kStepMask = 0x7FFF;

bool is_long(std::uint32_t step) noexcept {
  return step - 1 >= kStepMask;
}

template <typename T>
std::uint16_t* put_raw(std::uint16_t* out, T value) noexcept {
  std::memcpy(out, &value, sizeof(T));
  return out + sizeof(T) / 2;
}

// Where a look-up is: the last word, the count of words with kMany so far,
// the next long step, and how many of the query's words it found.
struct LookUpState {
  std::uint32_t word;
  std::uint32_t many;
  const std::uint16_t* long_step;
  std::size_t found;
};

// Looks words [first, last) up one by one; with kWords, writes the ids of
// the words found in place of their positions.
template <bool kCompact, bool kPopcnt, bool kWords = false>
[[gnu::always_inline]] inline void look_up_words(const std::uint16_t* steps, std::size_t first,
                                                 std::size_t last, const QueryWordSet& query,
                                                 LookUpState& state, std::uint32_t* positions,
                                                 std::uint32_t* details) {
  const std::uint32_t absent = query.absent();
  std::uint32_t word = state.word;
  std::uint32_t many = state.many;
  const std::uint16_t* long_step = state.long_step;
  std::size_t found = state.found;
  for (std::size_t i = first; i < last; ++i) {
    const std::uint32_t code = steps[i];
    std::uint32_t step = code & kStepMask;
    if (step == 0) {
      step = long_step[0] | std::uint32_t{long_step[1]} << 16;
      long_step += 2;
    }
    word += step;
    auto detail = static_cast<std::uint32_t>(i);
    if constexpr (kCompact) {
      const std::uint32_t flag = code >> 15;
      many += flag;
      detail = many & (0u - flag);
    }
    const std::uint32_t q = query.position<kPopcnt>(word);
    positions[found] = kWords ? word : q;
    details[found] = detail;
    found += q != absent ? 1 : 0;
  }
  state = {word, many, long_step, found};
}

template <bool kPopcnt>
std::size_t look_up_scalar(bool compact, const std::uint16_t* steps, std::size_t words,
                           const QueryWordSet& query, std::uint32_t* positions,
                           std::uint32_t* details) {
  LookUpState state{~std::uint32_t{0}, 0, steps + words, 0};
  if (compact)
    look_up_words<true, kPopcnt>(steps, 0, words, query, state, positions, details);
  else
    look_up_words<false, kPopcnt>(steps, 0, words, query, state, positions, details);
  return state.found;
}

std::size_t look_up_portable(bool compact, bool /*long_steps*/, const std::uint16_t* steps,
                             std::size_t words, const QueryWordSet& query, std::uint32_t* positions,
                             std::uint32_t* details) {
  return look_up_scalar<false>(compact, steps, words, query, positions, details);
}

#if defined(BINBOW_X86_DISPATCH)
// The same with the popcnt instruction (the build targets any x86-64): a
// word's position costs one instruction instead of the portable bit count's
// ten.
[[gnu::target("popcnt")]] std::size_t look_up_popcnt(bool compact, bool /*long_steps*/,
                                                     const std::uint16_t* steps, std::size_t words,
                                                     const QueryWordSet& query,
                                                     std::uint32_t* positions,
                                                     std::uint32_t* details) {
  return look_up_scalar<true>(compact, steps, words, query, positions, details);
}

// For each 8-bit mask, the indices of its set bits in increasing order, 4
// bits each: the permutation that moves the chosen lanes first.
constexpr std::array<std::uint32_t, 256> compress_permutations() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t mask = 0; mask < 256; ++mask) {
    std::uint32_t packed = 0, k = 0;
    for (std::uint32_t lane = 0; lane < 8; ++lane)
      if (mask & (1u << lane)) packed |= lane << (4 * k++);
    table[mask] = packed;
  }
  return table;
}
constexpr std::array<std::uint32_t, 256> kCompress = compress_permutations();

// A record's bits, its low half (x86-64 is little-endian): one 32-bit load.
[[gnu::always_inline]] inline int bits_of(const std::uint64_t* record) {
  std::int32_t bits;
  std::memcpy(&bits, record, sizeof bits);
  return bits;
}

// 8 words at a time: their steps' prefix sum gives their ids (and, in the
// top byte, compact entries' running count of words with kMany), their bits
// are read from the query's bitmap, and the ids of the ones present are
// written in order; blocks with a long step, and the last words, go one by
// one. Then the ids found (a fifth to a half) become positions. Gather
// instructions were slower than 8 loads, and a rank counted in vector
// registers for every word slower than one counted for the words found.
template <bool kCompact, bool kLongSteps>
[[gnu::target("avx2,popcnt")]] std::size_t look_up_avx2(const std::uint16_t* steps,
                                                        std::size_t words,
                                                        const QueryWordSet& query,
                                                        std::uint32_t* positions,
                                                        std::uint32_t* details) {
  LookUpState state{~std::uint32_t{0}, 0, steps + words, 0};
  const __m256i last_block = _mm256_set1_epi32(static_cast<int>(query.blocks() - 1));
  const std::uint64_t* const records = query.records();
  const __m256i step_mask = _mm256_set1_epi32(kStepMask);
  const __m256i low_bits = _mm256_set1_epi32(31);
  const __m256i lane_7 = _mm256_set1_epi32(7);
  const __m256i lane_shifts = _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28);
  __m256i base_word = _mm256_set1_epi32(-1);
  __m256i base_many = _mm256_setzero_si256();
  __m256i index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  std::size_t i = 0;
  for (; i + 8 <= words; i += 8) {
    const __m256i code =
        _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(steps + i)));
    const __m256i step = _mm256_and_si256(code, step_mask);
    if (kLongSteps && _mm256_movemask_epi8(_mm256_cmpeq_epi32(step, _mm256_setzero_si256())) != 0) {
      state.word = static_cast<std::uint32_t>(_mm256_cvtsi256_si32(base_word));
      state.many = static_cast<std::uint32_t>(_mm256_cvtsi256_si32(base_many));
      look_up_words<kCompact, true, true>(steps, i, i + 8, query, state, positions, details);
      base_word = _mm256_set1_epi32(static_cast<int>(state.word));
      base_many = _mm256_set1_epi32(static_cast<int>(state.many));
      index = _mm256_add_epi32(index, _mm256_set1_epi32(8));
      continue;
    }
    // Each lane's step (below 2^15, so 8 sum below 2^18) and, in compact
    // entries, its kMany flag at bit 24; then their sums up to each lane.
    __m256i sums = step;
    if constexpr (kCompact)
      sums = _mm256_add_epi32(step, _mm256_slli_epi32(_mm256_srli_epi32(code, 15), 24));
    sums = _mm256_add_epi32(sums, _mm256_slli_si256(sums, 4));
    sums = _mm256_add_epi32(sums, _mm256_slli_si256(sums, 8));
    const __m256i low_total =
        _mm256_shuffle_epi32(_mm256_permute2x128_si256(sums, sums, 0x08), 0xFF);
    sums = _mm256_add_epi32(sums, low_total);
    __m256i word;
    __m256i detail;
    if constexpr (kCompact) {
      word = _mm256_add_epi32(base_word, _mm256_and_si256(sums, _mm256_set1_epi32(0xFFFFFF)));
      const __m256i many = _mm256_add_epi32(base_many, _mm256_srli_epi32(sums, 24));
      detail = _mm256_and_si256(many, _mm256_srai_epi32(_mm256_slli_epi32(code, 16), 31));
      base_many = _mm256_permutevar8x32_epi32(many, lane_7);
    } else {
      word = _mm256_add_epi32(base_word, sums);
      detail = index;
      index = _mm256_add_epi32(index, _mm256_set1_epi32(8));
    }
    base_word = _mm256_permutevar8x32_epi32(word, lane_7);
    // Each word's bits; none beyond the bitmap.
    const __m256i block = _mm256_srli_epi32(word, 5);
    const __m256i clamped = _mm256_min_epu32(block, last_block);
    alignas(32) std::uint32_t at[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(at), clamped);
    const __m256i loaded = _mm256_setr_epi32(bits_of(records + at[0]), bits_of(records + at[1]),
                                             bits_of(records + at[2]), bits_of(records + at[3]),
                                             bits_of(records + at[4]), bits_of(records + at[5]),
                                             bits_of(records + at[6]), bits_of(records + at[7]));
    const __m256i bits = _mm256_and_si256(loaded, _mm256_cmpeq_epi32(clamped, block));
    const __m256i present =
        _mm256_slli_epi32(_mm256_srlv_epi32(bits, _mm256_and_si256(word, low_bits)), 31);
    const auto mask = static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(present)));
    const __m256i order =
        _mm256_srlv_epi32(_mm256_set1_epi32(static_cast<int>(kCompress[mask])), lane_shifts);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(positions + state.found),
                        _mm256_permutevar8x32_epi32(word, order));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(details + state.found),
                        _mm256_permutevar8x32_epi32(detail, order));
    state.found += static_cast<std::size_t>(__builtin_popcount(mask));
  }
  state.word = static_cast<std::uint32_t>(_mm256_cvtsi256_si32(base_word));
  state.many = static_cast<std::uint32_t>(_mm256_cvtsi256_si32(base_many));
  look_up_words<kCompact, true, true>(steps, i, words, query, state, positions, details);
  for (std::size_t k = 0; k < state.found; ++k)
    positions[k] = query.position_of_held<true>(positions[k]);
  return state.found;
}

[[gnu::target("avx2,popcnt")]] std::size_t look_up_avx2(
    bool compact, bool long_steps, const std::uint16_t* steps, std::size_t words,
    const QueryWordSet& query, std::uint32_t* positions, std::uint32_t* details) {
  // Most entries have no long step: their blocks need no check.
  if (compact)
    return long_steps ? look_up_avx2<true, true>(steps, words, query, positions, details)
                      : look_up_avx2<true, false>(steps, words, query, positions, details);
  return long_steps ? look_up_avx2<false, true>(steps, words, query, positions, details)
                    : look_up_avx2<false, false>(steps, words, query, positions, details);
}
#endif

using LookUp = std::size_t (*)(bool, bool, const std::uint16_t*, std::size_t, const QueryWordSet&,
                               std::uint32_t*, std::uint32_t*);

LookUp fastest_look_up() {
#if defined(BINBOW_X86_DISPATCH)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt")) return look_up_avx2;
  if (__builtin_cpu_supports("popcnt")) return look_up_popcnt;
#endif
  return look_up_portable;
}

}  // namespace

std::atomic<bool>& portable_forward_lookups() {
  static std::atomic<bool> portable{false};
  return portable;
}

std::size_t ForwardIndex::look_up(const std::uint16_t* codes, const QueryWordSet& query,
                                  std::uint32_t* positions, std::uint32_t* details) {
  static const LookUp fastest = fastest_look_up();
  const bool compact = codes[0] == kCounts;
  const std::uint16_t* const steps = codes + (compact ? kCountsHeader : kFloatsHeader);
  const std::uint32_t words = read<std::uint32_t>(codes + kWordsAt);
  const LookUp chosen =
      portable_forward_lookups().load(std::memory_order_relaxed) ? look_up_portable : fastest;
  const bool long_steps = read<std::uint32_t>(codes + kLongStepsAt) != 0;
  return chosen(compact, long_steps, steps, words, query, positions, details);
}

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
  std::uint32_t long_steps = 0;
  std::size_t many = 0;
  std::uint32_t previous = ~std::uint32_t{0};
  for (std::size_t i = 0; i < n; ++i) {
    long_steps += is_long(words[i].word - previous) ? 1 : 0;
    previous = words[i].word;
    if (counts != nullptr) many += counts[i] > 1 ? 1 : 0;
  }
  const std::size_t size = counts != nullptr
                               ? kCountsHeader + n + 2 * std::size_t{long_steps} + 1 + many
                               : kFloatsHeader + n + 2 * std::size_t{long_steps} + 2 * n;
  std::vector<std::uint16_t> codes(size);
  codes[0] = counts != nullptr ? kCounts : kFloats;
  put_raw(codes.data() + kWordsAt, static_cast<std::uint32_t>(n));
  put_raw(codes.data() + kLongStepsAt, long_steps);
  if (counts != nullptr) put_raw(codes.data() + kDivisorAt, form->divisor());
  std::uint16_t* step = codes.data() + (counts != nullptr ? kCountsHeader : kFloatsHeader);
  std::uint16_t* long_step = step + n;
  previous = ~std::uint32_t{0};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t delta = words[i].word - previous;
    previous = words[i].word;
    const std::uint16_t flag = counts != nullptr && counts[i] > 1 ? kMany : 0;
    if (is_long(delta)) {
      *step++ = flag;
      long_step = put_raw(long_step, delta);
    } else {
      *step++ = static_cast<std::uint16_t>(delta | flag);
    }
  }
  std::uint16_t* out = long_step;
  if (counts != nullptr) {
    *out++ = 1;  // the count of the words without kMany
    for (std::size_t i = 0; i < n; ++i)
      if (counts[i] > 1) *out++ = static_cast<std::uint16_t>(counts[i]);
    return codes;
  }
  for (std::size_t i = 0; i < n; ++i) out = put_raw(out, words[i].value);
  return codes;
}

}  // namespace binbow::detail
