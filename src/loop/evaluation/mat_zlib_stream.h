// The zlib stream of a compressed .mat variable, inflated from the file one
// piece at a time: what both the element check and the one-pass dense
// reader walk, so that neither keeps more than a piece in memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <zlib.h>

namespace binbow::loop::detail {

class MatZlibStream {
 public:
  // Inflates the `compressed_bytes` that follow `in`'s position. Errors are
  // FileErrors naming `path` and the variable at byte `offset`.
  MatZlibStream(std::ifstream& in, const std::string& path, std::uint64_t offset,
                std::uint64_t compressed_bytes, std::size_t input_chunk, std::size_t output_chunk);
  ~MatZlibStream();
  MatZlibStream(const MatZlibStream&) = delete;
  MatZlibStream& operator=(const MatZlibStream&) = delete;

  // Inflates the next piece (call only while !ended()); it may be empty.
  void next();
  bool ended() const noexcept { return ended_; }
  const unsigned char* piece() const noexcept { return output_.data(); }
  std::size_t piece_size() const noexcept { return piece_size_; }
  // The stream position of the piece's first byte, and of its end.
  std::uint64_t piece_start() const noexcept { return inflated_ - piece_size_; }
  std::uint64_t inflated() const noexcept { return inflated_; }
  // Whether compressed bytes remain after the end of the stream.
  bool trailing_bytes() const noexcept { return left_ != 0 || stream_.avail_in != 0; }

  [[noreturn]] void fail(const std::string& what) const;

 private:
  std::ifstream& in_;
  const std::string& path_;
  std::uint64_t offset_;
  std::uint64_t left_;
  z_stream stream_{};
  std::vector<unsigned char> input_, output_;
  std::size_t piece_size_ = 0;
  std::uint64_t inflated_ = 0;
  bool ended_ = false;
};

}  // namespace binbow::loop::detail
