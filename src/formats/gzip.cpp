#include "formats/gzip.h"

#include <zlib.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <memory>

#include "binbow/error.h"

namespace binbow::detail {

std::size_t gunzip_limit(std::size_t compressed_size) {
  if (compressed_size > kGunzipMaxLimit / kGunzipMaxRatio) return kGunzipMaxLimit;
  return std::max(kGunzipMinLimit, compressed_size * kGunzipMaxRatio);
}

namespace {

// Output chunks start at 1 MiB and then double the output so far: few chunks,
// and pages the data never reaches are never touched (new[] does not clear).
constexpr std::size_t kFirstChunk = std::size_t{1} << 20;

struct Chunk {
  std::unique_ptr<std::uint8_t[]> bytes;
  std::size_t capacity = 0;
  std::size_t used = 0;
};

}  // namespace

std::vector<std::uint8_t> gunzip(const std::uint8_t* data, std::size_t size,
                                 const std::string& name, std::size_t limit) {
  z_stream stream{};
  if (inflateInit2(&stream, 15 + 16) != Z_OK)  // 15 + 16: gzip wrapper, 32 KiB window
    throw FileError(name, "cannot initialise zlib");
  std::vector<Chunk> chunks;
  std::size_t produced = 0;
  std::size_t consumed = 0;
  const auto fail = [&](const std::string& problem) {
    inflateEnd(&stream);
    throw FileError(name, problem);
  };
  const auto fail_too_large = [&] {
    fail("gzip data expands beyond " + std::to_string(limit) +
         " bytes, more than any real vocabulary of this compressed size (corrupt or hostile "
         "file; if it is genuine, decompress it with gunzip and load the plain file)");
  };
  for (;;) {
    if (chunks.empty() || chunks.back().used == chunks.back().capacity) {
      // One byte beyond the limit tells a stream that ends exactly at it from
      // one that goes on.
      const std::size_t room = limit + 1 - produced;
      const std::size_t capacity = std::min(room, std::max(kFirstChunk, produced));
      chunks.push_back({std::unique_ptr<std::uint8_t[]>(new std::uint8_t[capacity]), capacity, 0});
    }
    Chunk& chunk = chunks.back();
    const std::size_t input = std::min<std::size_t>(size - consumed, UINT_MAX);
    const std::size_t room = std::min<std::size_t>(chunk.capacity - chunk.used, UINT_MAX);
    stream.next_in = const_cast<Bytef*>(data + consumed);
    stream.avail_in = static_cast<uInt>(input);
    stream.next_out = chunk.bytes.get() + chunk.used;
    stream.avail_out = static_cast<uInt>(room);
    const int status = inflate(&stream, Z_NO_FLUSH);
    consumed += input - stream.avail_in;
    chunk.used += room - stream.avail_out;
    produced += room - stream.avail_out;
    if (produced > limit) fail_too_large();
    if (status == Z_STREAM_END) {
      // Concatenated members (as `cat a.gz b.gz`) form one gzip file; trailing
      // zero padding is tolerated as gzip(1) does.
      std::size_t rest = consumed;
      while (rest < size && data[rest] == 0) ++rest;
      if (rest == size) break;
      if (inflateReset(&stream) != Z_OK) fail("cannot reset zlib");
      continue;
    }
    if (status != Z_OK && status != Z_BUF_ERROR)
      fail(std::string("gzip data is corrupt (") + (stream.msg ? stream.msg : "zlib error") + ")");
    // Output room left, so inflate stopped for want of input.
    if (consumed == size && stream.avail_out != 0) fail("gzip data is truncated");
  }
  inflateEnd(&stream);
  std::vector<std::uint8_t> out(produced);
  std::size_t at = 0;
  for (Chunk& chunk : chunks) {
    if (chunk.used > 0) std::memcpy(out.data() + at, chunk.bytes.get(), chunk.used);
    at += chunk.used;
    chunk.bytes.reset();
  }
  return out;
}

std::vector<std::uint8_t> gunzip_head(const std::uint8_t* data, std::size_t size,
                                      std::size_t want) {
  std::vector<std::uint8_t> out(want);
  z_stream stream{};
  if (inflateInit2(&stream, 15 + 16) != Z_OK) return {};
  stream.next_in = const_cast<Bytef*>(data);
  stream.avail_in = static_cast<uInt>(std::min<std::size_t>(size, UINT_MAX));
  stream.next_out = out.data();
  stream.avail_out = static_cast<uInt>(want);
  int status = Z_OK;
  while (status == Z_OK && stream.avail_out > 0) status = inflate(&stream, Z_NO_FLUSH);
  out.resize(want - stream.avail_out);
  inflateEnd(&stream);
  return out;
}

std::vector<std::uint8_t> gzip(const std::vector<std::uint8_t>& data) {
  z_stream stream{};
  if (deflateInit2(&stream, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw Error("cannot initialise zlib");
  std::vector<std::uint8_t> out(deflateBound(&stream, data.size()) + 64);
  stream.next_in = const_cast<Bytef*>(data.data());
  stream.avail_in = static_cast<uInt>(data.size());
  stream.next_out = out.data();
  stream.avail_out = static_cast<uInt>(out.size());
  // One call suffices: the output buffer holds deflateBound bytes. Inputs over
  // 4 GiB are fed in pieces.
  std::size_t fed = std::min<std::size_t>(data.size(), UINT_MAX);
  stream.avail_in = static_cast<uInt>(fed);
  int status = Z_OK;
  while (status != Z_STREAM_END) {
    if (stream.avail_in == 0 && fed < data.size()) {
      const std::size_t next = std::min<std::size_t>(data.size() - fed, UINT_MAX);
      stream.next_in = const_cast<Bytef*>(data.data() + fed);
      stream.avail_in = static_cast<uInt>(next);
      fed += next;
    }
    status = deflate(&stream, fed == data.size() ? Z_FINISH : Z_NO_FLUSH);
    if (status != Z_OK && status != Z_STREAM_END && status != Z_BUF_ERROR) {
      deflateEnd(&stream);
      throw Error("gzip compression failed");
    }
  }
  out.resize(stream.total_out);
  deflateEnd(&stream);
  return out;
}

}  // namespace binbow::detail
