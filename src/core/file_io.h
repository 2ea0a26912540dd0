// File access shared by every reader and writer: whole-file mapping with
// clear errors, and atomic replacement on save.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace binbow::detail {

// "a FIFO", "a directory", "a socket", "a device", ... for the file type bits
// of a stat mode: what a path names when it is not a regular file.
const char* file_kind(unsigned mode);

// A read-only memory map of a whole file. Throws FileError naming the file
// when it is missing, a directory, not a regular file (a FIFO, a socket, a
// device: refused without blocking), unreadable or empty.
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
  // Drops the whole pages within [begin, begin + size) from the process's
  // resident memory; touching them again reads them back (from the page
  // cache, usually). A large file read once in order then never occupies
  // memory as a whole.
  void release(const std::uint8_t* begin, std::size_t size) const noexcept;

 private:
  std::string path_;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

// Writes through `write` (called with a FILE* opened on a temporary file in the
// destination's directory), flushes it to disk (fsync), then renames it over
// `path` and flushes the directory: readers never see a half-written file,
// and after a power loss the name holds the old or the new content. A
// symbolic link at `path` is written through: the file it points to is
// replaced, the link stays. Missing folders on the way to `path` are created
// (detail::prepare_output_file). Throws FileError naming `path`.
//
// The temporary is "<destination>.tmp-XXXXXX", flock()ed while its writer
// lives; every save first removes the unlocked temporaries of its
// destination, which writers killed before their rename left behind.
void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write);
void write_file_atomically(const std::string& path, const void* data, std::size_t size);

// One file of a group for write_files_atomically.
struct FileToWrite {
  std::string path;
  std::function<void(std::FILE*)> write;
};

class TemporaryFile;

// Files that belong together (a result and its description), written over a
// while and replacing their destinations together or not at all. stage()
// gives each a temporary beside its destination, as write_file_atomically
// does (links followed, flock()ed, swept by a later save if its writer is
// killed); commit() flushes every temporary to disk, then renames them in
// order, and if a rename fails puts back what the earlier ones replaced.
// Destroyed without a commit (a write failed, a full disk), it removes its
// temporaries and every destination stays as it was.
class StagedFiles {
 public:
  StagedFiles();
  StagedFiles(const StagedFiles&) = delete;
  StagedFiles& operator=(const StagedFiles&) = delete;
  ~StagedFiles();

  // The temporary of `path`, open for writing until commit() or destruction.
  // Throws FileError naming `path`.
  std::FILE* stage(const std::string& path);
  // Throws FileError naming the file that could not be written or replaced.
  void commit();

 private:
  std::vector<std::unique_ptr<TemporaryFile>> temporaries_;
};

// StagedFiles for contents written at once.
void write_files_atomically(const std::vector<FileToWrite>& files);

// Writes all bytes or throws FileError naming `path`.
void write_all(std::FILE* file, const void* data, std::size_t size, const std::string& path);

}  // namespace binbow::detail
