// gzip through zlib, with the decompressed size capped so that a small
// hostile file (a "gzip bomb") cannot claim unbounded memory or time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace binbow::detail {

inline bool is_gzip(const std::uint8_t* data, std::size_t size) {
  return size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
}

// The most a gzip-compressed vocabulary of `compressed_size` bytes may expand
// to, whatever the format inside: kGunzipMaxRatio times its size, at least
// kGunzipMinLimit, at most kGunzipMaxLimit. Real vocabularies compress 1.1x
// (binary) to 7x (text); deflate reaches 1032x only on long repetitions,
// which no real vocabulary has (docs/formats.md, "Limits").
inline constexpr std::size_t kGunzipMaxRatio = 64;
inline constexpr std::size_t kGunzipMinLimit = std::size_t{16} << 20;
inline constexpr std::size_t kGunzipMaxLimit = std::size_t{4} << 30;
std::size_t gunzip_limit(std::size_t compressed_size);

// Decompresses a whole gzip file (concatenated members allowed, `limit`
// applying to their total). Inflates in chunks that grow with the output, so
// memory follows the real output (twice it at most, while the chunks are
// joined), never the size the trailer claims. Throws FileError(name, ...)
// when the data is corrupt, truncated or expands beyond `limit`.
std::vector<std::uint8_t> gunzip(const std::uint8_t* data, std::size_t size,
                                 const std::string& name, std::size_t limit);

// At most the first `want` decompressed bytes (fewer if the data ends or is
// corrupt): enough to recognise what a gzip file holds without inflating it.
std::vector<std::uint8_t> gunzip_head(const std::uint8_t* data, std::size_t size, std::size_t want);

std::vector<std::uint8_t> gzip(const std::vector<std::uint8_t>& data);

}  // namespace binbow::detail
