#include "core/file_io.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <utility>
#include <vector>

#include "binbow/error.h"
#include "core/output_path.h"
#include "core/warnings.h"

namespace binbow::detail {

namespace {
std::string errno_text() {
  return std::strerror(errno);
}
}  // namespace

const char* file_kind(unsigned mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISREG(mode)) return "a regular file";
  return "a special file";
}

std::string resolve_symlinks(const std::string& path) {
  constexpr int kMaxSymlinkHops = 40;  // as the kernel's ELOOP limit
  std::string current = path;
  for (int hop = 0; hop < kMaxSymlinkHops; ++hop) {
    struct stat st {};
    if (::lstat(current.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return current;
    std::error_code error;
    const std::filesystem::path target = std::filesystem::read_symlink(current, error);
    if (error)
      throw FileError(path, "cannot read the symbolic link " + current + ": " + error.message());
    current = target.is_absolute()
                  ? target.string()
                  : (std::filesystem::path(current).parent_path() / target).string();
  }
  throw FileError(path, "too many levels of symbolic links");
}

std::atomic<bool>& refuse_mappings() {
  static std::atomic<bool> refuse{false};
  return refuse;
}

MappedFile::MappedFile(const std::string& path, bool populate) : path_(path) {
  // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw FileError(path, "cannot open: " + errno_text());
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const std::string why = errno_text();
    ::close(fd);
    throw FileError(path, "cannot stat: " + why);
  }
  if (S_ISDIR(st.st_mode)) {
    ::close(fd);
    throw FileError(path, "is a directory, expected a file");
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    throw FileError(path, std::string("is ") + file_kind(st.st_mode) + ", not a regular file");
  }
  if (st.st_size <= 0) {
    ::close(fd);
    throw FileError(path, "file is empty");
  }
  size_ = static_cast<std::size_t>(st.st_size);
  device_ = st.st_dev;
  inode_ = st.st_ino;
  void* map = MAP_FAILED;
  if (refuse_mappings().load(std::memory_order_relaxed))
    errno = ENODEV;  // what a file system without mmap answers
  else
    map = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE | (populate ? MAP_POPULATE : 0), fd, 0);
  if (map != MAP_FAILED) {
    ::close(fd);
    data_ = static_cast<const std::uint8_t*>(map);
    return;
  }
  // A file system that cannot map (some FUSE and network mounts): the file
  // is read into memory instead, which costs its size in memory and time.
  const std::string why = errno_text();
  auto* copy = static_cast<std::uint8_t*>(std::malloc(size_));
  if (copy == nullptr) {
    ::close(fd);
    throw FileError(path, "cannot map into memory (" + why + ") nor allocate " +
                              std::to_string(size_) + " bytes to read it");
  }
  for (std::size_t done = 0; done < size_;) {
    const ssize_t got = ::pread(fd, copy + done, size_ - done, static_cast<off_t>(done));
    if (got <= 0) {
      const std::string read_why = got == 0 ? "the file shrank while read" : errno_text();
      std::free(copy);
      ::close(fd);
      throw FileError(path, "cannot map into memory (" + why + ") nor read: " + read_why);
    }
    done += static_cast<std::size_t>(got);
  }
  ::close(fd);
  data_ = copy;
  read_ = true;
}

void MappedFile::unmap() noexcept {
  if (data_ == nullptr) return;
  if (read_)
    std::free(const_cast<std::uint8_t*>(data_));
  else
    ::munmap(const_cast<std::uint8_t*>(data_), size_);
}

void MappedFile::release(const std::uint8_t* begin, std::size_t size) const noexcept {
  if (read_) return;
  const auto page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
  const auto first = (reinterpret_cast<std::uintptr_t>(begin) + page - 1) / page * page;
  const auto end = (reinterpret_cast<std::uintptr_t>(begin) + size) / page * page;
  // Advice only: if it fails, the pages simply stay resident.
  if (end > first) (void)::madvise(reinterpret_cast<void*>(first), end - first, MADV_DONTNEED);
}

bool MappedFile::still_at(const std::string& path) const noexcept {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && st.st_dev == device_ && st.st_ino == inode_;
}
MappedFile::MappedFile(MappedFile&& other) noexcept
    : path_(std::move(other.path_)),
      device_(other.device_),
      inode_(other.inode_),
      data_(other.data_),
      size_(other.size_),
      read_(other.read_) {
  other.data_ = nullptr;
  other.size_ = 0;
}

MappedFile& MappedFile::operator=(MappedFile&& other) noexcept {
  if (this != &other) {
    unmap();
    path_ = std::move(other.path_);
    device_ = other.device_;
    inode_ = other.inode_;
    data_ = other.data_;
    size_ = other.size_;
    read_ = other.read_;
    other.data_ = nullptr;
    other.size_ = 0;
  }
  return *this;
}

MappedFile::~MappedFile() {
  unmap();
}

void write_all(std::FILE* file, const void* data, std::size_t size, const std::string& path) {
  if (size > 0 && std::fwrite(data, 1, size, file) != size)
    throw FileError(path, "cannot write: " + errno_text());
}

void start_writeback(std::FILE* file, std::size_t offset, std::size_t size) noexcept {
  if (std::fflush(file) != 0) return;  // write_all reports errors; this is advice
  (void)::sync_file_range(::fileno(file), static_cast<off64_t>(offset), static_cast<off64_t>(size),
                          SYNC_FILE_RANGE_WRITE);
}

ReplaceCalls& replace_calls() {
  static ReplaceCalls calls{::link, std::rename, ::unlink};
  return calls;
}

namespace {

constexpr char kTemporaryInfix[] = ".tmp-";
constexpr char kBackupInfix[] = ".old-";
constexpr std::size_t kRandomSuffixLength = 6;  // mkstemp's XXXXXX
constexpr int kAttempts = 10;

// An open file descriptor, closed (and its flock released) when it dies.
class Descriptor {
 public:
  Descriptor() noexcept = default;
  explicit Descriptor(int fd) noexcept : fd_(fd) {}
  Descriptor(Descriptor&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  Descriptor& operator=(Descriptor&& other) noexcept {
    if (this != &other) {
      if (fd_ >= 0) ::close(fd_);
      fd_ = std::exchange(other.fd_, -1);
    }
    return *this;
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const noexcept { return fd_; }
  bool valid() const noexcept { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

std::string directory_of(const std::string& path) {
  const std::string parent = std::filesystem::path(path).parent_path().string();
  return parent.empty() ? "." : parent;
}

bool has_random_suffix(const std::string& name, const std::string& prefix) {
  if (name.size() != prefix.size() + kRandomSuffixLength || name.compare(0, prefix.size(), prefix))
    return false;
  return std::all_of(name.begin() + static_cast<std::ptrdiff_t>(prefix.size()), name.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; });
}

// The files beside `target` named "<target><infix>XXXXXX".
std::vector<std::string> siblings(const std::string& target, const char* infix) {
  std::vector<std::string> found;
  const std::string directory = directory_of(target);
  const std::string prefix = std::filesystem::path(target).filename().string() + infix;
  DIR* dir = ::opendir(directory.c_str());
  if (dir == nullptr) return found;
  while (const dirent* entry = ::readdir(dir))
    if (has_random_suffix(entry->d_name, prefix)) found.push_back(directory + "/" + entry->d_name);
  ::closedir(dir);
  return found;
}

// `path` opened and exclusively locked when it is a regular file no live
// save holds: every save keeps a lock on its temporaries and backups until
// it is done with them, so one that can be locked was left by a save that
// died (kill -9, power loss). Invalid when it cannot be opened or locked
// (another user's file, a file system without locks): it is left alone.
Descriptor lock_abandoned(const std::string& path, struct stat& st) {
  Descriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK));
  if (fd.valid() && ::fstat(fd.get(), &st) == 0 && S_ISREG(st.st_mode) &&
      ::flock(fd.get(), LOCK_EX | LOCK_NB) == 0)
    return fd;
  return Descriptor();
}

// Removes the temporaries of `target` that dead saves left: half-written
// files, never anything else's only copy.
void remove_stale_temporaries(const std::string& target) {
  for (const std::string& path : siblings(target, kTemporaryInfix)) {
    struct stat st {};
    const Descriptor lock = lock_abandoned(path, st);
    if (lock.valid()) ::unlink(path.c_str());
  }
}

bool same_file(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

bool modified_before(const struct stat& a, const struct stat& b) {
  return a.st_mtim.tv_sec != b.st_mtim.tv_sec ? a.st_mtim.tv_sec < b.st_mtim.tv_sec
                                              : a.st_mtim.tv_nsec < b.st_mtim.tv_nsec;
}

// Moves `from` to the free name `to`; false if `to` exists or the move fails.
bool move_to_free_name(const std::string& from, const std::string& to) {
  if (::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0) return true;
  if (errno != EINVAL && errno != ENOSYS) return false;
  // A file system without RENAME_NOREPLACE: link() never replaces either.
  return ::link(from.c_str(), to.c_str()) == 0 && ::unlink(from.c_str()) == 0;
}

// Deals with the backups of `target` that dead saves left (see
// keep_previous). A backup is removed only when the destination makes it
// redundant: it is the destination itself (a second link), or the
// destination is not older than it (the save that made it went through).
// When the destination is missing, its newest backup is the only copy of
// the data and is put back in its place. Any other backup stays.
void sweep_backups(const std::string& target) {
  struct Abandoned {
    std::string path;
    struct stat st;
    Descriptor lock;
  };
  std::vector<Abandoned> abandoned;
  for (std::string& path : siblings(target, kBackupInfix)) {
    struct stat st {};
    Descriptor lock = lock_abandoned(path, st);
    if (lock.valid()) abandoned.push_back({std::move(path), st, std::move(lock)});
  }
  if (abandoned.empty()) return;
  struct stat destination {};
  bool exists = ::lstat(target.c_str(), &destination) == 0;
  if (!exists && errno == ENOENT) {
    const auto newest = std::max_element(
        abandoned.begin(), abandoned.end(),
        [](const Abandoned& a, const Abandoned& b) { return modified_before(a.st, b.st); });
    if (move_to_free_name(newest->path, target)) abandoned.erase(newest);
    exists = ::lstat(target.c_str(), &destination) == 0;
  }
  for (const Abandoned& backup : abandoned)
    if (exists && (same_file(backup.st, destination) || !modified_before(destination, backup.st)))
      ::unlink(backup.path.c_str());
}

mode_t new_file_mode() {
  // mkstemp creates 0600; files get the permissions the user's umask asks for.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  return 0666 & ~mask;
}

void sync_directory(const std::string& directory, const std::string& path) {
  const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw FileError(path, "cannot open its directory to flush it: " + errno_text());
  // Some file systems cannot sync a directory (EINVAL); the rename stands.
  const bool synced = ::fsync(fd) == 0 || errno == EINVAL;
  const std::string why = errno_text();
  ::close(fd);
  if (!synced) throw FileError(path, "cannot flush its directory to disk: " + why);
}

// A locked "<destination>.tmp-XXXXXX"; removed unless renamed.
class TemporaryFile {
 public:
  TemporaryFile(const std::string& path, const std::string& destination) : path_(path) {
    for (int attempt = 0;; ++attempt) {
      temporary_ = destination + kTemporaryInfix + std::string(kRandomSuffixLength, 'X');
      const int fd = ::mkstemp(temporary_.data());
      if (fd < 0)
        throw FileError(path_, "cannot create a temporary file beside it: " + errno_text());
      if (owns(fd)) {
        file_ = ::fdopen(fd, "wb");
        if (file_ == nullptr) {
          const std::string why = errno_text();
          ::close(fd);
          ::unlink(temporary_.c_str());
          throw FileError(path_, "cannot open a temporary file: " + why);
        }
        return;
      }
      // Another save took it for stale between mkstemp and flock and removes it.
      ::close(fd);
      if (attempt == kAttempts) throw FileError(path_, "cannot keep a temporary file beside it");
    }
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile() {
    if (file_ != nullptr) std::fclose(file_);
    if (!renamed_) ::unlink(temporary_.c_str());
  }

  std::FILE* file() const { return file_; }

  // All bytes on disk, with permissions `mode`.
  void flush(mode_t mode) const {
    if (std::fflush(file_) != 0 || ::fsync(::fileno(file_)) != 0)
      throw FileError(path_, "cannot write: " + errno_text());
    if (::fchmod(::fileno(file_), mode) != 0)
      throw FileError(path_, "cannot give the new file its permissions: " + errno_text());
  }
  // Renamed while still open, so the lock covers the file until it is closed.
  void rename_to(const std::string& target) {
    if (replace_calls().rename(temporary_.c_str(), target.c_str()) != 0)
      throw FileError(path_, "cannot replace the file: " + errno_text());
    renamed_ = true;
  }

 private:
  // Whether this save holds `fd`'s temporary: locked, and not removed by a
  // concurrent stale-temporary sweep in the meantime.
  static bool owns(int fd) {
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) return errno != EWOULDBLOCK;  // no locks here: go on
    struct stat st {};
    return ::fstat(fd, &st) == 0 && st.st_nlink > 0;
  }

  std::string path_;  // as the caller named it, for errors
  std::string temporary_;
  std::FILE* file_ = nullptr;
  bool renamed_ = false;
};

// The previous version of a destination while a group replaces it, to put
// back if a later file of the group fails: "<destination>.old-XXXXXX",
// locked from its creation until the group is done (see sweep_backups).
struct Backup {
  std::string path;  // empty: the destination did not exist
  Descriptor lock;
};

// Reserves a fresh name beside `destination` for its previous version.
std::string backup_name(const std::string& destination, const std::string& path) {
  std::string name = destination + kBackupInfix + std::string(kRandomSuffixLength, 'X');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) throw FileError(path, "cannot create a file beside it: " + errno_text());
  ::close(fd);
  ::unlink(name.c_str());
  return name;
}

// A copy of `current` (open on the destination) named `name`, for file
// systems without hard links: written whole as a temporary, with the
// destination's permissions and times, then renamed.
Backup copy_backup(const Descriptor& current, const struct stat& st, const std::string& destination,
                   const std::string& name, const std::string& path) {
  TemporaryFile copy(path, destination);
  std::vector<char> buffer(std::size_t{1} << 16);
  for (;;) {
    const ssize_t n = ::read(current.get(), buffer.data(), buffer.size());
    if (n == 0) break;
    if (n < 0 && errno == EINTR) continue;
    if (n < 0)
      throw FileError(path, "cannot read it to keep its previous version: " + errno_text());
    write_all(copy.file(), buffer.data(), static_cast<std::size_t>(n), path);
  }
  copy.flush(st.st_mode & 07777);
  const timespec times[2] = {st.st_atim, st.st_mtim};
  ::futimens(::fileno(copy.file()), times);
  Descriptor lock(::fcntl(::fileno(copy.file()), F_DUPFD_CLOEXEC, 0));
  copy.rename_to(name);
  return {name, std::move(lock)};
}

// Keeps the destination's current version under a backup name before it is
// replaced, without ever moving the destination itself: a second hard link,
// or a copy where links are not supported. Either way the backup is locked
// from birth (the link through a lock on the destination's inode taken
// before linking), and has the destination's modification time.
Backup keep_previous(const std::string& destination, const std::string& path) {
  for (int attempt = 0;; ++attempt) {
    Descriptor current(::open(destination.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK));
    if (!current.valid() && errno == ENOENT) return {};
    if (!current.valid())
      throw FileError(path, "cannot open it to keep its previous version: " + errno_text());
    struct stat st {};
    if (::fstat(current.get(), &st) != 0)
      throw FileError(path, "cannot stat it to keep its previous version: " + errno_text());
    if (S_ISDIR(st.st_mode)) throw FileError(path, "cannot replace it: it is a directory");
    // Shared: saves of the same file at once each keep their own backup.
    ::flock(current.get(), LOCK_SH);
    const std::string name = backup_name(destination, path);
    if (replace_calls().link(destination.c_str(), name.c_str()) != 0)
      return copy_backup(current, st, destination, name, path);
    struct stat linked {};
    if (::lstat(name.c_str(), &linked) == 0 && same_file(linked, st))
      return {name, std::move(current)};
    // Another save replaced the destination between open and link: the lock
    // held is on the file before it.
    ::unlink(name.c_str());
    if (attempt == kAttempts)
      throw FileError(path, "cannot keep its previous version: it keeps being replaced");
  }
}

// Puts a replaced destination's previous version back.
void restore(const std::string& destination, const Backup& backup) {
  if (backup.path.empty())
    replace_calls().unlink(destination.c_str());
  else
    replace_calls().rename(backup.path.c_str(), destination.c_str());
}

// A non-regular output written in place (see is_written_in_place): the
// process's own descriptor shared (its offset, its append mode), any other
// opened for writing (a FIFO waits for its reader, as a shell would).
std::FILE* open_in_place(const std::string& path) {
  const int own = own_descriptor(path);
  const int fd = own >= 0 ? ::fcntl(own, F_DUPFD_CLOEXEC, 0)
                          : ::open(path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) throw FileError(path, "cannot open it for writing: " + errno_text());
  std::FILE* file = ::fdopen(fd, "wb");
  if (file == nullptr) {
    const std::string why = errno_text();
    ::close(fd);
    throw FileError(path, "cannot open it for writing: " + why);
  }
  return file;
}

}  // namespace

// One file of a StagedFiles: a temporary beside its destination, replacing
// it at commit, or a character device or FIFO written in place.
class StagedFile {
 public:
  explicit StagedFile(const std::string& path) : path_(path) {
    if (is_written_in_place(path)) {
      in_place_ = open_in_place(path);
      return;
    }
    destination_ = resolve_symlinks(path);
    remove_stale_temporaries(destination_);
    sweep_backups(destination_);
    temporary_ = std::make_unique<TemporaryFile>(path, destination_);
  }
  StagedFile(const StagedFile&) = delete;
  StagedFile& operator=(const StagedFile&) = delete;
  ~StagedFile() {
    if (in_place_ != nullptr) std::fclose(in_place_);
  }

  std::FILE* file() const { return in_place_ != nullptr ? in_place_ : temporary_->file(); }
  bool in_place() const { return in_place_ != nullptr; }
  const std::string& path() const { return path_; }
  const std::string& destination() const { return destination_; }

  void flush() const {
    if (temporary_ != nullptr)
      temporary_->flush(new_file_mode());
    else if (std::fflush(in_place_) != 0)
      throw FileError(path_, "cannot write: " + errno_text());
  }
  void replace() { temporary_->rename_to(destination_); }

 private:
  std::string path_;         // as the caller named it, for errors
  std::string destination_;  // symbolic links resolved
  std::unique_ptr<TemporaryFile> temporary_;
  std::FILE* in_place_ = nullptr;
};

StagedFiles::StagedFiles() = default;
StagedFiles::~StagedFiles() = default;

std::FILE* StagedFiles::stage(const std::string& path) {
  prepare_output_file(path);
  files_.push_back(std::make_unique<StagedFile>(path));
  return files_.back()->file();
}

void StagedFiles::commit() {
  for (const auto& file : files_) file->flush();
  std::vector<const StagedFile*> replaced;
  std::vector<Backup> backups;
  const auto undo = [&] {
    for (std::size_t i = backups.size(); i-- > 0;) restore(replaced[i]->destination(), backups[i]);
  };
  for (const auto& file : files_) {
    if (file->in_place()) continue;
    Backup backup;
    try {
      backup = keep_previous(file->destination(), file->path());
      file->replace();
    } catch (const FileError&) {
      // The destination never left its place: only the backup goes.
      if (!backup.path.empty()) replace_calls().unlink(backup.path.c_str());
      undo();
      throw;
    }
    replaced.push_back(file.get());
    backups.push_back(std::move(backup));
  }
  // Committed: from here on a failure leaves the new files in place, so it
  // is reported as a warning, not as an error that a retry would repeat.
  for (std::size_t i = 0; i < backups.size(); ++i)
    if (!backups[i].path.empty() && replace_calls().unlink(backups[i].path.c_str()) != 0)
      warn(replaced[i]->path() + ": saved, but its previous version stays as " + backups[i].path +
           " (" + errno_text() + "); the next save of it removes it");
  backups.clear();
  // The renames reach the disk with their directories.
  for (const StagedFile* file : replaced) {
    try {
      sync_directory(directory_of(file->destination()), file->path());
    } catch (const FileError& e) {
      warn(e.path() + ": saved, but " + e.problem() + ": a power loss may still undo the save");
    }
  }
  files_.clear();
}

void sweep_leftovers(const std::string& path) {
  const std::string destination = resolve_symlinks(path);
  remove_stale_temporaries(destination);
  sweep_backups(destination);
}

void write_files_atomically(const std::vector<FileToWrite>& files) {
  StagedFiles staged;
  for (const FileToWrite& file : files) file.write(staged.stage(file.path));
  staged.commit();
}

void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write) {
  write_files_atomically({{path, write}});
}

void write_file_atomically(const std::string& path, const void* data, std::size_t size) {
  write_file_atomically(path, [&](std::FILE* file) { write_all(file, data, size, path); });
}

}  // namespace binbow::detail
