// gzip through zlib, with the decompressed size capped so that a small
// hostile file (a "gzip bomb") cannot claim unbounded memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace binbow::detail {

inline bool is_gzip(const std::uint8_t* data, std::size_t size) {
  return size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
}

// Deflate cannot expand data more than 1032-fold; anything claiming more is
// corrupt or hostile. Also capped absolutely at 4 GiB.
std::size_t gunzip_limit(std::size_t compressed_size);

// Decompresses a whole gzip file (concatenated members allowed). Throws
// FileError(name, ...) when it is corrupt, truncated or expands beyond `limit`.
std::vector<std::uint8_t> gunzip(const std::uint8_t* data, std::size_t size,
                                 const std::string& name, std::size_t limit);

// At most the first `want` decompressed bytes (fewer if the data ends or is
// corrupt): enough to recognise what a gzip file holds without inflating it.
std::vector<std::uint8_t> gunzip_head(const std::uint8_t* data, std::size_t size, std::size_t want);

std::vector<std::uint8_t> gzip(const std::vector<std::uint8_t>& data);

}  // namespace binbow::detail
