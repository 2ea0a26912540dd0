// File access shared by every reader and writer: whole-file mapping with
// clear errors, and atomic replacement on save.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace binbow::detail {

// A read-only memory map of a whole file. Throws FileError naming the file
// when it is missing, a directory, unreadable or empty.
class MappedFile {
 public:
  // `populate`: fault every page in at once, faster when all of it is read.
  explicit MappedFile(const std::string& path, bool populate = false);
  MappedFile(MappedFile&& other) noexcept;
  MappedFile& operator=(MappedFile&& other) noexcept;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile();

  const std::uint8_t* data() const noexcept { return data_; }
  std::size_t size() const noexcept { return size_; }
  const std::string& path() const noexcept { return path_; }

 private:
  std::string path_;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

// Writes through `write` (called with a FILE* opened on a temporary file in the
// destination's directory), flushes, then renames over `path`: readers never
// see a half-written file. Throws FileError naming `path`.
void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write);
void write_file_atomically(const std::string& path, const void* data, std::size_t size);

// Writes all bytes or throws FileError naming `path`.
void write_all(std::FILE* file, const void* data, std::size_t size, const std::string& path);

}  // namespace binbow::detail
