#include "core/crc32c.h"

#include <array>
#include <cstring>

namespace binbow::detail {

#if defined(BINBOW_X86_DISPATCH)
std::uint32_t crc32c_sse42(const void* data, std::size_t size, std::uint32_t crc);
#endif

namespace {

constexpr std::uint32_t kPolynomial = 0x82f63b78u;  // reflected Castagnoli

using Tables = std::array<std::array<std::uint32_t, 256>, 8>;

Tables make_tables() {
  Tables t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ ((c & 1u) ? kPolynomial : 0u);
    t[0][i] = c;
  }
  for (std::uint32_t i = 0; i < 256; ++i)
    for (std::size_t s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xffu];
  return t;
}

std::uint32_t table_crc(const void* data, std::size_t size, std::uint32_t crc) {
  static const Tables t = make_tables();
  const auto* p = static_cast<const std::uint8_t*>(data);
  std::uint32_t c = ~crc;
  while (size >= 8) {
    std::uint32_t lo, hi;
    std::memcpy(&lo, p, 4);
    std::memcpy(&hi, p + 4, 4);
    lo ^= c;
    c = t[7][lo & 0xff] ^ t[6][(lo >> 8) & 0xff] ^ t[5][(lo >> 16) & 0xff] ^ t[4][lo >> 24] ^
        t[3][hi & 0xff] ^ t[2][(hi >> 8) & 0xff] ^ t[1][(hi >> 16) & 0xff] ^ t[0][hi >> 24];
    p += 8;
    size -= 8;
  }
  while (size-- > 0) c = (c >> 8) ^ t[0][(c ^ *p++) & 0xffu];
  return ~c;
}

using CrcFunction = std::uint32_t (*)(const void*, std::size_t, std::uint32_t);

CrcFunction choose() {
#if defined(BINBOW_X86_DISPATCH)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("sse4.2")) return &crc32c_sse42;
#endif
  return &table_crc;
}

// Multiplies a 32×32 matrix over GF(2) (one column per bit) by a vector.
std::uint32_t gf2_times(const std::uint32_t* matrix, std::uint32_t vector) {
  std::uint32_t sum = 0;
  for (int bit = 0; vector != 0; ++bit, vector >>= 1)
    if (vector & 1u) sum ^= matrix[bit];
  return sum;
}

void gf2_square(std::uint32_t* square, const std::uint32_t* matrix) {
  for (int n = 0; n < 32; ++n) square[n] = gf2_times(matrix, matrix[n]);
}

}  // namespace

std::uint32_t crc32c_portable(const void* data, std::size_t size, std::uint32_t crc) {
  return table_crc(data, size, crc);
}

// Appending len zero bytes to A is a linear map of crc(A); apply it by
// repeated squaring of the one-zero-bit operator, then add crc(B).
std::uint32_t crc32c_combine(std::uint32_t crc_a, std::uint32_t crc_b, std::size_t size_b) {
  if (size_b == 0) return crc_a;
  std::uint32_t odd[32], even[32];
  odd[0] = kPolynomial;
  for (int n = 1; n < 32; ++n) odd[n] = 1u << (n - 1);
  gf2_square(even, odd);  // two zero bits
  gf2_square(odd, even);  // four zero bits
  for (;;) {
    gf2_square(even, odd);
    if (size_b & 1u) crc_a = gf2_times(even, crc_a);
    size_b >>= 1;
    if (size_b == 0) break;
    gf2_square(odd, even);
    if (size_b & 1u) crc_a = gf2_times(odd, crc_a);
    size_b >>= 1;
    if (size_b == 0) break;
  }
  return crc_a ^ crc_b;
}

std::uint32_t crc32c(const void* data, std::size_t size, std::uint32_t crc) {
  static const CrcFunction function = choose();
  return function(data, size, crc);
}

}  // namespace binbow::detail
