// CRC-32C (Castagnoli), the checksum of every section of binbow's files.
// Uses the SSE4.2 instruction when the CPU has it, a table otherwise.
#pragma once

#include <cstddef>
#include <cstdint>

namespace binbow::detail {

// CRC of `size` bytes, continuing from `crc` (0 to start).
std::uint32_t crc32c(const void* data, std::size_t size, std::uint32_t crc = 0);
// The table-driven implementation, for tests that compare the two.
std::uint32_t crc32c_portable(const void* data, std::size_t size, std::uint32_t crc = 0);
// CRC of A followed by B, from crc(A), crc(B) and B's length.
std::uint32_t crc32c_combine(std::uint32_t crc_a, std::uint32_t crc_b, std::size_t size_b);

}  // namespace binbow::detail
