// Compiled with -msse4.2 on x86-64; called only when the CPU has SSE4.2.
#if defined(BINBOW_X86_DISPATCH)
#include <nmmintrin.h>

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace binbow::detail {

std::uint32_t crc32c_sse42(const void* data, std::size_t size, std::uint32_t crc) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  std::uint64_t c = ~crc;
  while (size >= 8) {
    std::uint64_t v;
    std::memcpy(&v, p, 8);
    c = _mm_crc32_u64(c, v);
    p += 8;
    size -= 8;
  }
  auto c32 = static_cast<std::uint32_t>(c);
  while (size-- > 0) c32 = _mm_crc32_u8(c32, *p++);
  return ~c32;
}

}  // namespace binbow::detail
#endif
