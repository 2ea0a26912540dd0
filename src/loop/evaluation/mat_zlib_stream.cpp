#include "loop/evaluation/mat_zlib_stream.h"

#include <algorithm>

#include "binbow/error.h"

namespace binbow::loop::detail {

MatZlibStream::MatZlibStream(std::ifstream& in, const std::string& path, std::uint64_t offset,
                             std::uint64_t compressed_bytes, std::size_t input_chunk,
                             std::size_t output_chunk)
    : in_(in),
      path_(path),
      offset_(offset),
      left_(compressed_bytes),
      input_(input_chunk),
      output_(output_chunk) {
  if (inflateInit(&stream_) != Z_OK) fail("cannot start zlib");
}

MatZlibStream::~MatZlibStream() {
  inflateEnd(&stream_);
}

void MatZlibStream::fail(const std::string& what) const {
  throw FileError(path_, "variable at byte " + std::to_string(offset_) + ": " + what);
}

void MatZlibStream::next() {
  if (stream_.avail_in == 0) {
    if (left_ == 0) fail("a compressed variable that ends before its zlib stream");
    const auto chunk = static_cast<std::size_t>(std::min<std::uint64_t>(left_, input_.size()));
    if (!in_.read(reinterpret_cast<char*>(input_.data()), static_cast<std::streamsize>(chunk)))
      fail("a compressed variable cut short");
    left_ -= chunk;
    stream_.next_in = input_.data();
    stream_.avail_in = static_cast<uInt>(chunk);
  }
  stream_.next_out = output_.data();
  stream_.avail_out = static_cast<uInt>(output_.size());
  const int status = inflate(&stream_, Z_NO_FLUSH);
  if (status != Z_OK && status != Z_STREAM_END)
    fail("a compressed variable whose zlib stream is damaged");
  ended_ = status == Z_STREAM_END;
  piece_size_ = output_.size() - stream_.avail_out;
  inflated_ += piece_size_;
}

}  // namespace binbow::loop::detail
