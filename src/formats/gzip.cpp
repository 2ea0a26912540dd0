#include "formats/gzip.h"

#include <zlib.h>

#include <algorithm>
#include <climits>

#include "binbow/error.h"

namespace binbow::detail {

std::size_t gunzip_limit(std::size_t compressed_size) {
  constexpr std::size_t kMaxRatio = 1032;
  constexpr std::size_t kAbsoluteLimit = std::size_t{4} << 30;
  if (compressed_size > kAbsoluteLimit / kMaxRatio) return kAbsoluteLimit;
  return compressed_size * kMaxRatio + 4096;
}

std::vector<std::uint8_t> gunzip(const std::uint8_t* data, std::size_t size,
                                 const std::string& name, std::size_t limit) {
  z_stream stream{};
  if (inflateInit2(&stream, 15 + 16) != Z_OK)  // 15 + 16: gzip wrapper, 32 KiB window
    throw FileError(name, "cannot initialise zlib");
  std::vector<std::uint8_t> out;
  // The trailer's ISIZE (size mod 4 GiB of the last member) is a good first
  // guess; the buffer still grows, up to `limit`, if it is wrong.
  std::size_t guess = size * 4;
  if (size >= 18)
    guess =
        std::max<std::size_t>(guess, data[size - 4] | data[size - 3] << 8 | data[size - 2] << 16 |
                                         std::size_t{data[size - 1]} << 24);
  out.resize(std::min(limit, std::max<std::size_t>(guess + 1, 1 << 16)));
  std::size_t produced = 0;
  std::size_t consumed = 0;
  const auto fail = [&](const std::string& problem) {
    inflateEnd(&stream);
    throw FileError(name, problem);
  };
  for (;;) {
    if (produced == out.size()) {
      if (out.size() >= limit)
        fail("gzip data expands beyond " + std::to_string(limit) +
             " bytes, more than a valid file of this size can (corrupt or hostile file)");
      out.resize(std::min(limit, out.size() * 2));
    }
    const std::size_t input = std::min<std::size_t>(size - consumed, UINT_MAX);
    const std::size_t room = std::min<std::size_t>(out.size() - produced, UINT_MAX);
    stream.next_in = const_cast<Bytef*>(data + consumed);
    stream.avail_in = static_cast<uInt>(input);
    stream.next_out = out.data() + produced;
    stream.avail_out = static_cast<uInt>(room);
    const int status = inflate(&stream, Z_NO_FLUSH);
    consumed += input - stream.avail_in;
    produced += room - stream.avail_out;
    if (status == Z_STREAM_END) {
      // Concatenated members (as `cat a.gz b.gz`) form one gzip file; trailing
      // zero padding is tolerated as gzip(1) does.
      std::size_t rest = consumed;
      while (rest < size && data[rest] == 0) ++rest;
      if (rest == size) break;
      if (inflateReset(&stream) != Z_OK) fail("cannot reset zlib");
      continue;
    }
    if (status == Z_BUF_ERROR && consumed == size) fail("gzip data is truncated");
    if (status != Z_OK && status != Z_BUF_ERROR)
      fail(std::string("gzip data is corrupt (") + (stream.msg ? stream.msg : "zlib error") + ")");
    if (consumed == size && stream.avail_out != 0) fail("gzip data is truncated");
  }
  inflateEnd(&stream);
  out.resize(produced);
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
