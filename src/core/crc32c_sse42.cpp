// Compiled with -msse4.2 on x86-64; called only when the CPU has SSE4.2.
#if defined(BINBOW_X86_DISPATCH)
#include <nmmintrin.h>

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/crc32c.h"

namespace binbow::detail {

namespace {

std::uint64_t load64(const std::uint8_t* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

std::uint32_t one_stream(const std::uint8_t* p, std::size_t size, std::uint32_t crc) {
  std::uint64_t c = ~crc;
  for (; size >= 8; size -= 8, p += 8) c = _mm_crc32_u64(c, load64(p));
  auto c32 = static_cast<std::uint32_t>(c);
  while (size-- > 0) c32 = _mm_crc32_u8(c32, *p++);
  return ~c32;
}

}  // namespace

// The crc32 instruction has a latency of three cycles and a throughput of
// one: three independent streams over thirds of the buffer keep it busy, and
// their CRCs are combined at the end.
std::uint32_t crc32c_sse42(const void* data, std::size_t size, std::uint32_t crc) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  constexpr std::size_t kMinimumForStreams = 3 * 4096;
  if (size < kMinimumForStreams) return one_stream(p, size, crc);
  const std::size_t third = size / 3 / 8 * 8;
  const std::uint8_t* a = p;
  const std::uint8_t* b = p + third;
  const std::uint8_t* c = p + 2 * third;
  std::uint64_t ca = ~crc, cb = ~0u, cc = ~0u;
  for (std::size_t i = 0; i < third; i += 8) {
    ca = _mm_crc32_u64(ca, load64(a + i));
    cb = _mm_crc32_u64(cb, load64(b + i));
    cc = _mm_crc32_u64(cc, load64(c + i));
  }
  const std::size_t rest = size - 3 * third;
  std::uint32_t result = ~static_cast<std::uint32_t>(ca);
  result = crc32c_combine(result, ~static_cast<std::uint32_t>(cb), third);
  const std::uint32_t tail = one_stream(p + 3 * third, rest, ~static_cast<std::uint32_t>(cc));
  return crc32c_combine(result, tail, third + rest);
}

}  // namespace binbow::detail
#endif
