// Kernel bodies, included once per instruction set by kernels_<isa>.cpp with
// BINBOW_KERNEL_NAMESPACE defined, and BINBOW_KERNEL_AVX2, BINBOW_KERNEL_AVX512
// or BINBOW_KERNEL_NEON for the vector code of one instruction set. These are
// set by the file rather than read from the compiler's __AVX2__ and the like,
// so that a build for this machine's CPU (-march=native) still compiles the
// portable kernels as they are; the compile flags of the file decide whether
// __builtin_popcountll becomes one instruction.
#include <cstring>

#if defined(BINBOW_KERNEL_AVX512)
#if !defined(__AVX512F__) || !defined(__AVX512VPOPCNTDQ__)
#error "kernels_avx512.cpp needs -mavx512f -mavx512vpopcntdq"
#endif
#include <immintrin.h>
#elif defined(BINBOW_KERNEL_AVX2)
#if !defined(__AVX2__) || !defined(__POPCNT__)
#error "kernels_avx2.cpp needs -mavx2 -mpopcnt"
#endif
#include <immintrin.h>
#elif defined(BINBOW_KERNEL_NEON)
#if !defined(__aarch64__)
#error "kernels_neon.cpp is for aarch64 only"
#endif
#include <arm_neon.h>
#endif

#include "core/kernels.h"

namespace binbow::detail::BINBOW_KERNEL_NAMESPACE {
namespace {

inline std::uint64_t load64(const std::uint8_t* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

inline std::uint32_t popcount64(std::uint64_t x) {
#if defined(__POPCNT__) || !defined(__x86_64__)
  return static_cast<std::uint32_t>(__builtin_popcountll(x));
#else
  // Without the instruction GCC calls a libgcc routine; SWAR is faster.
  x -= (x >> 1) & 0x5555555555555555ull;
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<std::uint32_t>((x * 0x0101010101010101ull) >> 56);
#endif
}

#if defined(BINBOW_KERNEL_AVX2)
// The bit count of each byte of v: two 16-entry lookups, one per nibble.
inline __m256i byte_counts(__m256i v) {
  const __m256i table = _mm256_setr_epi8(0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4,  //
                                         0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4);
  const __m256i nibble = _mm256_set1_epi8(0x0f);
  return _mm256_add_epi8(
      _mm256_shuffle_epi8(table, _mm256_and_si256(v, nibble)),
      _mm256_shuffle_epi8(table, _mm256_and_si256(_mm256_srli_epi16(v, 4), nibble)));
}

inline __m256i load256(const std::uint8_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}
#endif

// One pair of fixed-width descriptors. With AVX2 this stays scalar: for a
// single pair, four or eight popcnt instructions are faster than a vector
// count followed by a horizontal sum.
template <std::size_t N>
inline std::uint32_t hamming_fixed(const std::uint8_t* a, const std::uint8_t* b) {
#if defined(BINBOW_KERNEL_NEON)
  // aarch64 has no scalar population count: one vector count per 16 bytes.
  // A byte of the sum holds at most 8 · N / 16 ≤ 32.
  uint8x16_t counts = vcntq_u8(veorq_u8(vld1q_u8(a), vld1q_u8(b)));
  for (std::size_t i = 16; i < N; i += 16)
    counts = vaddq_u8(counts, vcntq_u8(veorq_u8(vld1q_u8(a + i), vld1q_u8(b + i))));
  return vaddlvq_u8(counts);
#else
  std::uint32_t d = 0;
  for (std::size_t i = 0; i < N; i += 8) d += popcount64(load64(a + i) ^ load64(b + i));
  return d;
#endif
}

inline std::uint32_t hamming_any(const std::uint8_t* a, const std::uint8_t* b, std::size_t n) {
  std::uint32_t d = 0;
  std::size_t i = 0;
#if defined(BINBOW_KERNEL_AVX2)
  if (n >= 32) {
    __m256i sums = _mm256_setzero_si256();
    for (; i + 32 <= n; i += 32)
      sums = _mm256_add_epi64(
          sums, _mm256_sad_epu8(byte_counts(_mm256_xor_si256(load256(a + i), load256(b + i))),
                                _mm256_setzero_si256()));
    const __m128i half =
        _mm_add_epi64(_mm256_castsi256_si128(sums), _mm256_extracti128_si256(sums, 1));
    d = static_cast<std::uint32_t>(
        _mm_cvtsi128_si64(_mm_add_epi64(half, _mm_unpackhi_epi64(half, half))));
  }
#elif defined(BINBOW_KERNEL_NEON)
  if (n >= 16) {
    uint32x4_t sums = vdupq_n_u32(0);
    for (; i + 16 <= n; i += 16)
      sums = vpadalq_u16(sums, vpaddlq_u8(vcntq_u8(veorq_u8(vld1q_u8(a + i), vld1q_u8(b + i)))));
    d = vaddvq_u32(sums);
  }
#endif
  for (; i + 8 <= n; i += 8) d += popcount64(load64(a + i) ^ load64(b + i));
  for (; i < n; ++i) d += popcount64(static_cast<std::uint64_t>(a[i] ^ b[i]));
  return d;
}

// Distance functor: fixed width when N > 0, run-time width otherwise.
template <std::size_t N>
struct Distance {
  std::size_t code_size;
  std::uint32_t operator()(const std::uint8_t* a, const std::uint8_t* b) const {
    if constexpr (N > 0) {
      return hamming_fixed<N>(a, b);
    } else {
      return hamming_any(a, b, code_size);
    }
  }
};

// Index of the nearest of `count` contiguous rows. The running minimum is
// over (distance, index) keys, so there is no unpredictable branch and ties go
// to the lowest index.
template <std::size_t N>
inline std::uint32_t nearest_row(const Distance<N>& distance, const std::uint8_t* query,
                                 const std::uint8_t* rows, std::size_t count,
                                 std::uint32_t* best_distance) {
  std::uint64_t best = ~std::uint64_t{0};
  for (std::size_t c = 0; c < count; ++c) {
    const std::uint64_t key =
        (std::uint64_t{distance(query, rows + c * distance.code_size)} << 32) | c;
    best = key < best ? key : best;
  }
  if (best_distance != nullptr) *best_distance = static_cast<std::uint32_t>(best >> 32);
  return static_cast<std::uint32_t>(best);
}

#if defined(BINBOW_KERNEL_AVX2)
#define BINBOW_KERNEL_BLOCKS 1
// A 32- or 64-byte query held in registers.
template <std::size_t N>
struct QueryRegisters {
  __m256i part[N / 32];
  explicit QueryRegisters(const std::uint8_t* query) {
    for (std::size_t i = 0; i < N / 32; ++i) part[i] = load256(query + 32 * i);
  }
};

// The bits of query ^ row as four 64-bit partial sums (at most 128 each).
template <std::size_t N>
inline __m256i partial_counts(const QueryRegisters<N>& q, const std::uint8_t* row) {
  __m256i counts = byte_counts(_mm256_xor_si256(q.part[0], load256(row)));
  if constexpr (N == 64)
    counts = _mm256_add_epi8(counts, byte_counts(_mm256_xor_si256(q.part[1], load256(row + 32))));
  return _mm256_sad_epu8(counts, _mm256_setzero_si256());
}

// Two rows' partial sums in one vector: the first row's in the low half of
// each 64-bit lane, the second's in the high half.
inline __m256i pair_sums(__m256i first, __m256i second) {
  return _mm256_or_si256(first, _mm256_slli_epi64(second, 32));
}

// The distances of the query to eight rows, as 32-bit lanes in row order.
template <std::size_t N>
inline __m256i distances8(const QueryRegisters<N>& q, const std::uint8_t* const* rows) {
  const __m256i r01 = pair_sums(partial_counts(q, rows[0]), partial_counts(q, rows[1]));
  const __m256i r23 = pair_sums(partial_counts(q, rows[2]), partial_counts(q, rows[3]));
  const __m256i r45 = pair_sums(partial_counts(q, rows[4]), partial_counts(q, rows[5]));
  const __m256i r67 = pair_sums(partial_counts(q, rows[6]), partial_counts(q, rows[7]));
  // Each 128-bit half: rows 0-3 (4-7), each over two of its four partial sums.
  const __m256i r0123 =
      _mm256_add_epi32(_mm256_unpacklo_epi64(r01, r23), _mm256_unpackhi_epi64(r01, r23));
  const __m256i r4567 =
      _mm256_add_epi32(_mm256_unpacklo_epi64(r45, r67), _mm256_unpackhi_epi64(r45, r67));
  return _mm256_add_epi32(_mm256_permute2x128_si256(r0123, r4567, 0x20),
                          _mm256_permute2x128_si256(r0123, r4567, 0x31));
}

inline void store8(__m256i distances, std::uint32_t* out) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), distances);
}

// The hot case with AVX2: eight children at a time, and the minimum taken
// over (distance, index) keys in a vector, so ties go to the lowest index as
// in the scalar kernel. The last count % 8 children are counted with popcnt:
// for k = 10 a second block would spend six of its eight rows on nothing.
template <std::size_t N>
inline std::uint32_t nearest_child(const std::uint8_t* query, const std::uint8_t* children,
                                   std::uint32_t count) {
  std::uint32_t best = ~0u;
  std::uint32_t base = 0;
  if (count >= 8) {
    const QueryRegisters<N> q(query);
    const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    __m256i keys = _mm256_set1_epi32(-1);
    for (; base + 8 <= count; base += 8) {
      const std::uint8_t* rows[8];
      for (std::uint32_t j = 0; j < 8; ++j) rows[j] = children + std::size_t{base + j} * N;
      const __m256i index = _mm256_add_epi32(lanes, _mm256_set1_epi32(static_cast<int>(base)));
      keys =
          _mm256_min_epu32(keys, _mm256_or_si256(_mm256_slli_epi32(distances8(q, rows), 8), index));
    }
    __m128i m = _mm_min_epu32(_mm256_castsi256_si128(keys), _mm256_extracti128_si256(keys, 1));
    m = _mm_min_epu32(m, _mm_shuffle_epi32(m, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm_min_epu32(m, _mm_shuffle_epi32(m, _MM_SHUFFLE(2, 3, 0, 1)));
    best = static_cast<std::uint32_t>(_mm_cvtsi128_si32(m));
  }
  for (; base < count; ++base) {
    const std::uint32_t key =
        (hamming_fixed<N>(query, children + std::size_t{base} * N) << 8) | base;
    best = key < best ? key : best;
  }
  return best & 0xffu;
}
#elif defined(BINBOW_KERNEL_NEON)
#define BINBOW_KERNEL_BLOCKS 1
template <std::size_t N>
struct QueryRegisters {
  uint8x16_t part[N / 16];
  explicit QueryRegisters(const std::uint8_t* query) {
    for (std::size_t i = 0; i < N / 16; ++i) part[i] = vld1q_u8(query + 16 * i);
  }
};

// The bit count of each byte of query ^ row, summed over the row's 16-byte
// parts: at most 16 per byte for 32-byte rows, 32 for 64-byte ones.
template <std::size_t N>
inline uint8x16_t byte_counts(const QueryRegisters<N>& q, const std::uint8_t* row) {
  uint8x16_t counts = vcntq_u8(veorq_u8(q.part[0], vld1q_u8(row)));
  for (std::size_t i = 1; i < N / 16; ++i)
    counts = vaddq_u8(counts, vcntq_u8(veorq_u8(q.part[i], vld1q_u8(row + 16 * i))));
  return counts;
}

// The distances of the query to eight rows, as 16-bit lanes in row order.
// Each pairwise addition halves the bytes per row; the sums are widened to
// 16 bits before they could pass 255.
template <std::size_t N>
inline uint16x8_t distances8(const QueryRegisters<N>& q, const std::uint8_t* const* rows) {
  const uint8x16_t r01 = vpaddq_u8(byte_counts(q, rows[0]), byte_counts(q, rows[1]));
  const uint8x16_t r23 = vpaddq_u8(byte_counts(q, rows[2]), byte_counts(q, rows[3]));
  const uint8x16_t r45 = vpaddq_u8(byte_counts(q, rows[4]), byte_counts(q, rows[5]));
  const uint8x16_t r67 = vpaddq_u8(byte_counts(q, rows[6]), byte_counts(q, rows[7]));
  const uint8x16_t r0123 = vpaddq_u8(r01, r23);  // four sums per row, ≤ 64 (≤ 128 for 64 bytes)
  const uint8x16_t r4567 = vpaddq_u8(r45, r67);
  if constexpr (N == 32) {
    return vpaddlq_u8(vpaddq_u8(r0123, r4567));
  } else {
    return vpaddq_u16(vpaddlq_u8(r0123), vpaddlq_u8(r4567));
  }
}

inline void store8(uint16x8_t distances, std::uint32_t* out) {
  vst1q_u32(out, vmovl_u16(vget_low_u16(distances)));
  vst1q_u32(out + 4, vmovl_high_u16(distances));
}

// The hot case with NEON: eight children at a time, and the minimum taken
// over (distance, index) keys in vectors, so ties go to the lowest index as
// in the scalar kernel. Rows past `count` are the query itself, read but
// never chosen: their keys are all ones.
template <std::size_t N>
inline std::uint32_t nearest_child(const std::uint8_t* query, const std::uint8_t* children,
                                   std::uint32_t count) {
  const QueryRegisters<N> q(query);
  static const std::uint32_t kLanes[4] = {0, 1, 2, 3};
  const uint32x4_t lanes = vld1q_u32(kLanes);
  const uint32x4_t limit = vdupq_n_u32(count);
  uint32x4_t best_low = vdupq_n_u32(~0u), best_high = best_low;
  for (std::uint32_t base = 0; base < count; base += 8) {
    const std::uint8_t* rows[8];
    for (std::uint32_t j = 0; j < 8; ++j)
      rows[j] = base + j < count ? children + std::size_t{base + j} * N : query;
    const uint16x8_t distances = distances8(q, rows);
    const uint32x4_t index_low = vaddq_u32(lanes, vdupq_n_u32(base));
    const uint32x4_t index_high = vaddq_u32(index_low, vdupq_n_u32(4));
    const uint32x4_t low = vorrq_u32(vorrq_u32(vshll_n_u16(vget_low_u16(distances), 8), index_low),
                                     vcgeq_u32(index_low, limit));
    const uint32x4_t high = vorrq_u32(vorrq_u32(vshll_high_n_u16(distances, 8), index_high),
                                      vcgeq_u32(index_high, limit));
    best_low = vminq_u32(best_low, low);
    best_high = vminq_u32(best_high, high);
  }
  return vminvq_u32(vminq_u32(best_low, best_high)) & 0xffu;
}
#elif defined(BINBOW_KERNEL_AVX512)
// Population counts of query ^ child for the children 2·pair and 2·pair + 1,
// as four 64-bit partial counts each: the first child in qwords 0-3, the
// second in 4-7. Children past `count` are masked loads that touch no memory.
template <std::size_t N>
inline __m512i pair_counts(__m512i query, const std::uint8_t* children, std::uint32_t pair,
                           std::uint32_t count) {
  const std::uint32_t first = 2 * pair;
  const bool whole = first + 1 < count;  // plain loads: the XOR can take them from memory
  const __mmask8 first_valid = first < count ? 0xff : 0;
  if constexpr (N == 32) {
    const std::uint8_t* rows = children + std::size_t{first} * 32;
    const __m512i loaded =
        whole ? _mm512_loadu_si512(rows) : _mm512_maskz_loadu_epi64(first_valid & 0x0f, rows);
    return _mm512_popcnt_epi64(_mm512_xor_si512(query, loaded));
  } else {
    const std::uint8_t* row = children + std::size_t{first} * 64;
    const __m512i a =
        _mm512_popcnt_epi64(_mm512_xor_si512(query, _mm512_maskz_loadu_epi64(first_valid, row)));
    const __m512i b = _mm512_popcnt_epi64(
        _mm512_xor_si512(query, whole ? _mm512_loadu_si512(row + 64) : _mm512_setzero_si512()));
    return _mm512_add_epi64(_mm512_shuffle_i64x2(a, b, _MM_SHUFFLE(1, 0, 1, 0)),
                            _mm512_shuffle_i64x2(a, b, _MM_SHUFFLE(3, 2, 3, 2)));
  }
}

// The hot case with AVX-512: eight children at a time, their distances
// reduced across registers in three steps, and the minimum taken over
// (distance, index) keys in a vector, so ties go to the lowest index as in
// the scalar kernel.
template <std::size_t N>
inline std::uint32_t nearest_child(const std::uint8_t* query, const std::uint8_t* children,
                                   std::uint32_t count) {
  __m512i q;
  if constexpr (N == 32) {
    q = _mm512_broadcast_i64x4(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(query)));
  } else {
    q = _mm512_loadu_si512(query);
  }
  // Lane i of the reduced vector holds child base + kOrder[i].
  const __m512i order = _mm512_set_epi64(7, 5, 6, 4, 3, 1, 2, 0);
  const __m512i limit = _mm512_set1_epi64(count);
  __m512i best = _mm512_set1_epi64(-1);
  for (std::uint32_t base = 0; base < count; base += 8) {
    const std::uint32_t pair = base / 2;
    // Whole groups for the common k = 8, 10, 16...; the tail computes only
    // the pairs it has (count is the same for every node of a tree, so these
    // branches are predicted).
    const std::uint32_t left = count - base;
    const __m512i zero = _mm512_setzero_si512();
    const __m512i p0 = pair_counts<N>(q, children, pair, count);
    const __m512i p1 = left > 2 ? pair_counts<N>(q, children, pair + 1, count) : zero;
    const __m512i p2 = left > 4 ? pair_counts<N>(q, children, pair + 2, count) : zero;
    const __m512i p3 = left > 6 ? pair_counts<N>(q, children, pair + 3, count) : zero;
    const __m512i t0 =
        _mm512_add_epi64(_mm512_unpacklo_epi64(p0, p1), _mm512_unpackhi_epi64(p0, p1));
    const __m512i t1 =
        _mm512_add_epi64(_mm512_unpacklo_epi64(p2, p3), _mm512_unpackhi_epi64(p2, p3));
    const __m512i distances =
        _mm512_add_epi64(_mm512_shuffle_i64x2(t0, t1, _MM_SHUFFLE(2, 0, 2, 0)),
                         _mm512_shuffle_i64x2(t0, t1, _MM_SHUFFLE(3, 1, 3, 1)));
    const __m512i index = _mm512_add_epi64(order, _mm512_set1_epi64(base));
    const __m512i keys = _mm512_or_si512(_mm512_slli_epi64(distances, 8), index);
    best = _mm512_mask_min_epu64(best, _mm512_cmplt_epu64_mask(index, limit), best, keys);
  }
  return static_cast<std::uint32_t>(_mm512_reduce_min_epu64(best)) & 0xffu;
}
#else
// The hot case: a 32- or 64-byte query held in registers against a block of
// at most 255 children, with 32-bit keys.
template <std::size_t N>
inline std::uint32_t nearest_child(const std::uint8_t* query, const std::uint8_t* children,
                                   std::uint32_t count) {
  std::uint64_t q[N / 8];
  for (std::size_t i = 0; i < N / 8; ++i) q[i] = load64(query + 8 * i);
  std::uint32_t best = ~0u;
  for (std::uint32_t c = 0; c < count; ++c) {
    const std::uint8_t* row = children + std::size_t{c} * N;
    std::uint32_t d = 0;
    for (std::size_t i = 0; i < N / 8; ++i) d += popcount64(q[i] ^ load64(row + 8 * i));
    const std::uint32_t key = (d << 8) | c;
    best = key < best ? key : best;
  }
  return best & 0xffu;
}

#endif

template <std::size_t N>
void nearest_impl(const std::uint8_t* queries, std::size_t n, const std::uint8_t* candidates,
                  std::size_t count, std::size_t code_size, std::uint32_t* best_index,
                  std::uint32_t* best_distance) {
#if defined(BINBOW_KERNEL_BLOCKS)
  // Eight candidates at a time, then the same (distance, index) keys as nearest_row.
  if constexpr (N > 0) {
    for (std::size_t q = 0; q < n; ++q) {
      const std::uint8_t* query = queries + q * N;
      const QueryRegisters<N> registers(query);
      std::uint64_t best = ~std::uint64_t{0};
      std::size_t c = 0;
      for (; c + 8 <= count; c += 8) {
        const std::uint8_t* rows[8];
        for (std::size_t j = 0; j < 8; ++j) rows[j] = candidates + (c + j) * N;
        std::uint32_t d[8];
        store8(distances8(registers, rows), d);
        for (std::size_t j = 0; j < 8; ++j) {
          const std::uint64_t key = (std::uint64_t{d[j]} << 32) | (c + j);
          best = key < best ? key : best;
        }
      }
      for (; c < count; ++c) {
        const std::uint64_t key =
            (std::uint64_t{hamming_fixed<N>(query, candidates + c * N)} << 32) | c;
        best = key < best ? key : best;
      }
      best_index[q] = static_cast<std::uint32_t>(best);
      if (best_distance != nullptr) best_distance[q] = static_cast<std::uint32_t>(best >> 32);
    }
    return;
  }
#endif
  const Distance<N> distance{code_size};
  for (std::size_t q = 0; q < n; ++q)
    best_index[q] = nearest_row(distance, queries + q * code_size, candidates, count,
                                best_distance != nullptr ? best_distance + q : nullptr);
}

inline void prefetch_block(const std::uint8_t* p, std::size_t bytes) {
  for (std::size_t off = 0; off < bytes; off += 64) __builtin_prefetch(p + off);
}

// Descends a batch of queries in lock step: while one query waits for its
// next children block to arrive from memory, the others compute, so cache
// misses of different queries overlap.
template <std::size_t N>
void descend_impl(const TreeView& tree, const std::uint8_t* queries, std::size_t n,
                  std::uint32_t* words, std::uint32_t* level_nodes, std::uint32_t level_depth) {
  constexpr std::size_t kBatch = 64;
  const std::size_t code_size = tree.code_size;
  const Distance<N> distance{code_size};
  for (std::size_t begin = 0; begin < n; begin += kBatch) {
    const std::size_t size = std::min(kBatch, n - begin);
    std::uint32_t node[kBatch], first[kBatch], count[kBatch], depth[kBatch];
    std::uint32_t active[kBatch];
    std::size_t active_count = size;
    for (std::size_t j = 0; j < size; ++j) {
      node[j] = 0;
      depth[j] = 0;
      active[j] = static_cast<std::uint32_t>(j);
      if (level_nodes != nullptr) level_nodes[begin + j] = 0;
    }
    while (active_count > 0) {
      std::size_t still = 0;
      for (std::size_t a = 0; a < active_count; ++a) {
        const std::uint32_t j = active[a];
        const std::uint32_t c = tree.child_counts[node[j]];
        if (c == 0) {
          words[begin + j] = tree.links[node[j]] & ~kLeafBit;
          if (level_nodes != nullptr && depth[j] < level_depth) level_nodes[begin + j] = node[j];
          continue;
        }
        first[j] = tree.links[node[j]];
        count[j] = c;
        // The children's links and counts come with their descriptors, so the
        // next level starts without a second dependent miss.
        prefetch_block(tree.descriptors + std::size_t{first[j]} * code_size, c * code_size);
        __builtin_prefetch(tree.links + first[j]);
        __builtin_prefetch(tree.child_counts + first[j]);
        active[still++] = j;
      }
      active_count = still;
      for (std::size_t a = 0; a < active_count; ++a) {
        const std::uint32_t j = active[a];
        const std::uint8_t* query = queries + (begin + j) * code_size;
        const std::uint8_t* children = tree.descriptors + std::size_t{first[j]} * code_size;
        std::uint32_t best_child;
        if constexpr (N > 0) {
          best_child = nearest_child<N>(query, children, count[j]);
        } else {
          best_child = nearest_row(distance, query, children, count[j], nullptr);
        }
        node[j] = first[j] + best_child;
        ++depth[j];
        if (level_nodes != nullptr && depth[j] == level_depth) level_nodes[begin + j] = node[j];
      }
    }
  }
}

std::uint32_t hamming(const std::uint8_t* a, const std::uint8_t* b, std::size_t code_size) {
  switch (code_size) {
    case 32:
      return hamming_fixed<32>(a, b);
    case 64:
      return hamming_fixed<64>(a, b);
    default:
      return hamming_any(a, b, code_size);
  }
}

void nearest(const std::uint8_t* queries, std::size_t n, const std::uint8_t* candidates,
             std::size_t count, std::size_t code_size, std::uint32_t* best_index,
             std::uint32_t* best_distance) {
  switch (code_size) {
    case 32:
      return nearest_impl<32>(queries, n, candidates, count, code_size, best_index, best_distance);
    case 64:
      return nearest_impl<64>(queries, n, candidates, count, code_size, best_index, best_distance);
    default:
      return nearest_impl<0>(queries, n, candidates, count, code_size, best_index, best_distance);
  }
}

template <std::size_t N>
void distances_impl(const std::uint8_t* query, const std::uint8_t* rows,
                    const std::uint32_t* indices, std::size_t count, std::size_t code_size,
                    std::uint32_t* out) {
#if defined(BINBOW_KERNEL_BLOCKS)
  if constexpr (N > 0) {
    const QueryRegisters<N> registers(query);
    std::size_t i = 0;
    for (; i + 8 <= count; i += 8) {
      const std::uint8_t* block[8];
      for (std::size_t j = 0; j < 8; ++j)
        block[j] = rows + (indices == nullptr ? i + j : std::size_t{indices[i + j]}) * N;
      store8(distances8(registers, block), out + i);
    }
    for (; i < count; ++i)
      out[i] =
          hamming_fixed<N>(query, rows + (indices == nullptr ? i : std::size_t{indices[i]}) * N);
    return;
  }
#endif
  const Distance<N> distance{code_size};
  if (indices == nullptr) {
    for (std::size_t i = 0; i < count; ++i) out[i] = distance(query, rows + i * code_size);
  } else {
    for (std::size_t i = 0; i < count; ++i)
      out[i] = distance(query, rows + std::size_t{indices[i]} * code_size);
  }
}

void distances(const std::uint8_t* query, const std::uint8_t* rows, const std::uint32_t* indices,
               std::size_t count, std::size_t code_size, std::uint32_t* out) {
  switch (code_size) {
    case 32:
      return distances_impl<32>(query, rows, indices, count, code_size, out);
    case 64:
      return distances_impl<64>(query, rows, indices, count, code_size, out);
    default:
      return distances_impl<0>(query, rows, indices, count, code_size, out);
  }
}

void descend(const TreeView& tree, const std::uint8_t* queries, std::size_t n, std::uint32_t* words,
             std::uint32_t* level_nodes, std::uint32_t level_depth) {
  switch (tree.code_size) {
    case 32:
      return descend_impl<32>(tree, queries, n, words, level_nodes, level_depth);
    case 64:
      return descend_impl<64>(tree, queries, n, words, level_nodes, level_depth);
    default:
      return descend_impl<0>(tree, queries, n, words, level_nodes, level_depth);
  }
}

}  // namespace

const Kernels& get() {
  static const Kernels kernels{BINBOW_KERNEL_NAME, &hamming, &nearest, &distances, &descend};
  return kernels;
}

}  // namespace binbow::detail::BINBOW_KERNEL_NAMESPACE
