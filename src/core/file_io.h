// File access shared by every reader and writer: whole-file mapping with
// clear errors, and atomic replacement on save.
#pragma once

#include <atomic>
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

// For tests: while set, MappedFile reads every file into memory, as where
// the file system cannot map it, so that the fallback runs where mapping works.
std::atomic<bool>& refuse_mappings();

// A read-only memory map of a whole file. Throws FileError naming the file
// when it is missing, a directory, not a regular file (a FIFO, a socket, a
// device: refused without blocking), unreadable or empty. Where the file
// system cannot map it, the file is read into memory instead (mapped() is
// then false). The mapping stays valid while the file is replaced by a
// rename (binbow's saves): it keeps the old inode. A file truncated or
// rewritten in place while mapped is undefined behaviour (SIGBUS).
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
  bool mapped() const noexcept { return !read_; }
  // Drops the whole pages within [begin, begin + size) from the process's
  // resident memory; touching them again reads them back (from the page
  // cache, usually). A large file read once in order then never occupies
  // memory as a whole.
  void release(const std::uint8_t* begin, std::size_t size) const noexcept;
  // Whether `path` (links followed) still names the file mapped: false once
  // a save has renamed another file over it.
  bool still_at(const std::string& path) const noexcept;

 private:
  void unmap() noexcept;

  std::string path_;
  std::uint64_t device_ = 0;
  std::uint64_t inode_ = 0;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
  bool read_ = false;  // malloc'd copy, not a mapping
};

// Writes through `write` (called with a FILE* opened on a temporary file in the
// destination's directory), flushes it to disk (fsync), then renames it over
// `path` and flushes the directory: readers never see a half-written file,
// and after a power loss the name holds the old or the new content. A
// symbolic link at `path` is written through: the file it points to is
// replaced, the link stays. Missing folders on the way to `path` are created
// (detail::prepare_output_file). Throws FileError naming `path`.
//
// A `path` that is not a regular file is never replaced
// (detail::is_written_in_place): a character device (/dev/null, a
// terminal) or a FIFO is opened and written in place, sequentially, as a
// shell redirection would (a FIFO waits for its reader); /dev/stdout,
// /dev/stderr and /dev/fd/N write through the process's own descriptor; a
// block device or a socket is refused.
//
// What a killed save leaves beside its destination is cleaned up by the
// next save of that destination, and only what it can prove is a dead
// save's: the temporary is "<destination>.tmp-XXXXXX", flock()ed while its
// writer lives, and removed by any later save that can lock it.
void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write);
void write_file_atomically(const std::string& path, const void* data, std::size_t size);

// One file of a group for write_files_atomically.
struct FileToWrite {
  std::string path;
  std::function<void(std::FILE*)> write;
};

class StagedFile;

// Files that belong together (a result and its description), written over a
// while and replacing their destinations together or not at all. stage()
// gives each a temporary beside its destination, as write_file_atomically
// does (links followed, flock()ed, swept by a later save if its writer is
// killed); commit() flushes every temporary to disk, then replaces the
// destinations in order, and if one fails puts back what the earlier ones
// replaced. Destroyed without a commit (a write failed, a full disk), it
// removes its temporaries and every destination stays as it was.
//
// Before a destination is replaced, its previous version is kept as
// "<destination>.old-XXXXXX": a second hard link, or where the file system
// has none a copy. The destination itself never moves, so whatever the file
// system and wherever a kill lands, a reader finds the old or the new file,
// never none. The backup is flock()ed from its creation until the commit
// ends. A later save of the destination that finds one unlocked (its save
// died) removes it only when it is redundant: the destination's own inode,
// or a destination modified since; with the destination missing, it puts the
// newest backup back in its place; any other backup stays. A kill between
// two renames leaves the group's earlier files new and its later ones old.
//
// Outputs written in place (see write_file_atomically) take no part in the
// all-or-nothing replacement: their bytes go out as they are written.
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
  std::vector<std::unique_ptr<StagedFile>> files_;
};

// What dead saves of `path` left beside it (temporaries, backups), dealt
// with as a save of `path` does before it writes.
void sweep_leftovers(const std::string& path);

// The file `path` finally names, following symbolic links (the last may
// dangle: the file is then created where it points). Throws FileError for a
// link that cannot be read or a loop.
std::string resolve_symlinks(const std::string& path);

// StagedFiles for contents written at once.
void write_files_atomically(const std::vector<FileToWrite>& files);

// The system calls that replace files, made through these pointers so that a
// test can make one fail (a file system without hard links) or stop the
// process just before one (a kill at that moment). Unless a test sets them
// they are ::link, ::rename and ::unlink.
struct ReplaceCalls {
  int (*link)(const char* from, const char* to);
  int (*rename)(const char* from, const char* to);
  int (*unlink)(const char* path);
};
ReplaceCalls& replace_calls();

// Writes all bytes or throws FileError naming `path`.
void write_all(std::FILE* file, const void* data, std::size_t size, const std::string& path);

// Asks the kernel to start writing the file's bytes [offset, offset + size)
// to disk now, without waiting for it (sync_file_range). Until a file's dirty
// pages pass a share of memory the kernel keeps them, so a save that writes
// a large file and then calls fsync would produce all its bytes first and
// only then wait for the disk: calling this every few MiB overlaps the two,
// and the fsync finds little left. Advice only: nothing happens where the
// kernel cannot.
void start_writeback(std::FILE* file, std::size_t offset, std::size_t size) noexcept;

}  // namespace binbow::detail
