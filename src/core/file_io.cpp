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

#include "binbow/error.h"
#include "core/output_path.h"

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
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISREG(mode)) return "a regular file";
  return "a special file";
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
  void* map = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE | (populate ? MAP_POPULATE : 0), fd, 0);
  ::close(fd);
  if (map == MAP_FAILED) throw FileError(path, "cannot map into memory: " + errno_text());
  data_ = static_cast<const std::uint8_t*>(map);
}

void MappedFile::release(const std::uint8_t* begin, std::size_t size) const noexcept {
  const auto page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
  const auto first = (reinterpret_cast<std::uintptr_t>(begin) + page - 1) / page * page;
  const auto end = (reinterpret_cast<std::uintptr_t>(begin) + size) / page * page;
  // Advice only: if it fails, the pages simply stay resident.
  if (end > first) (void)::madvise(reinterpret_cast<void*>(first), end - first, MADV_DONTNEED);
}

MappedFile::MappedFile(MappedFile&& other) noexcept
    : path_(std::move(other.path_)), data_(other.data_), size_(other.size_) {
  other.data_ = nullptr;
  other.size_ = 0;
}

MappedFile& MappedFile::operator=(MappedFile&& other) noexcept {
  if (this != &other) {
    if (data_ != nullptr) ::munmap(const_cast<std::uint8_t*>(data_), size_);
    path_ = std::move(other.path_);
    data_ = other.data_;
    size_ = other.size_;
    other.data_ = nullptr;
    other.size_ = 0;
  }
  return *this;
}

MappedFile::~MappedFile() {
  if (data_ != nullptr) ::munmap(const_cast<std::uint8_t*>(data_), size_);
}

void write_all(std::FILE* file, const void* data, std::size_t size, const std::string& path) {
  if (size > 0 && std::fwrite(data, 1, size, file) != size)
    throw FileError(path, "cannot write: " + errno_text());
}

namespace {

constexpr char kTemporaryInfix[] = ".tmp-";
constexpr std::size_t kTemporarySuffixLength = 6;  // mkstemp's XXXXXX
constexpr int kMaxSymlinkHops = 40;                // as the kernel's ELOOP limit

std::string directory_of(const std::string& path) {
  const std::string parent = std::filesystem::path(path).parent_path().string();
  return parent.empty() ? "." : parent;
}

// The file `path` finally names, following symbolic links (the last may
// dangle: the file is then created where it points).
std::string resolve_symlinks(const std::string& path) {
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

bool is_temporary_of(const std::string& name, const std::string& prefix) {
  if (name.size() != prefix.size() + kTemporarySuffixLength ||
      name.compare(0, prefix.size(), prefix))
    return false;
  return std::all_of(name.begin() + static_cast<std::ptrdiff_t>(prefix.size()), name.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; });
}

// Removes the temporaries of `target` that no live writer holds: a writer
// keeps an exclusive flock on its temporary until it has renamed it, so one
// that can be locked was left by a writer that died (kill -9, power loss).
// A file that cannot be opened or locked (another user's, a file system
// without locks) is left alone.
void remove_stale_temporaries(const std::string& target) {
  const std::string directory = directory_of(target);
  const std::string prefix = std::filesystem::path(target).filename().string() + kTemporaryInfix;
  DIR* dir = ::opendir(directory.c_str());
  if (dir == nullptr) return;
  while (const dirent* entry = ::readdir(dir)) {
    if (!is_temporary_of(entry->d_name, prefix)) continue;
    const std::string path = directory + "/" + entry->d_name;
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    if (fd < 0) continue;
    struct stat st {};
    if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && ::flock(fd, LOCK_EX | LOCK_NB) == 0)
      ::unlink(path.c_str());
    ::close(fd);
  }
  ::closedir(dir);
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

// The previous version of a destination while a group is renamed, to put
// back if a later rename fails.
struct Backup {
  std::string path;  // empty: the destination did not exist
  bool linked = false;
};

// Reserves a fresh name beside `destination` for its previous version.
std::string backup_name(const std::string& destination, const std::string& path) {
  std::string name = destination + ".old-XXXXXX";
  const int fd = ::mkstemp(name.data());
  if (fd < 0) throw FileError(path, "cannot create a file beside it: " + errno_text());
  ::close(fd);
  ::unlink(name.c_str());
  return name;
}

Backup keep_previous(const std::string& destination, const std::string& path) {
  Backup backup;
  struct stat st {};
  if (::lstat(destination.c_str(), &st) != 0) return backup;
  if (S_ISDIR(st.st_mode)) throw FileError(path, "cannot replace it: it is a directory");
  backup.path = backup_name(destination, path);
  // A second link keeps the destination in place until the rename replaces
  // it; where links are not supported it moves aside for that moment.
  if (::link(destination.c_str(), backup.path.c_str()) == 0) {
    backup.linked = true;
  } else if (std::rename(destination.c_str(), backup.path.c_str()) != 0) {
    throw FileError(path, "cannot keep the previous version while replacing it: " + errno_text());
  }
  return backup;
}

// Undoes keep_previous for a destination that was not replaced.
void drop_unused(const std::string& destination, const Backup& backup) {
  if (backup.linked)
    ::unlink(backup.path.c_str());
  else if (!backup.path.empty())
    std::rename(backup.path.c_str(), destination.c_str());
}

// Puts a replaced destination's previous version back.
void restore(const std::string& destination, const Backup& backup) {
  if (backup.path.empty())
    ::unlink(destination.c_str());
  else
    std::rename(backup.path.c_str(), destination.c_str());
}

}  // namespace

// A locked temporary beside a destination; removed unless renamed over it.
class TemporaryFile {
 public:
  TemporaryFile(const std::string& path, std::string destination)
      : path_(path), destination_(std::move(destination)) {
    remove_stale_temporaries(destination_);
    for (int attempt = 0;; ++attempt) {
      temporary_ = destination_ + kTemporaryInfix + std::string(kTemporarySuffixLength, 'X');
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
      if (attempt == 10) throw FileError(path_, "cannot keep a temporary file beside it");
    }
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile() {
    if (file_ != nullptr) std::fclose(file_);
    if (!renamed_) ::unlink(temporary_.c_str());
  }

  std::FILE* file() const { return file_; }
  const std::string& path() const { return path_; }
  const std::string& destination() const { return destination_; }

  // All bytes on disk, with the final permissions.
  void flush() const {
    if (std::fflush(file_) != 0 || ::fsync(::fileno(file_)) != 0)
      throw FileError(path_, "cannot write: " + errno_text());
    ::fchmod(::fileno(file_), new_file_mode());
  }
  // Renamed while still open, so the lock covers the temporary until it is gone.
  void rename() {
    if (std::rename(temporary_.c_str(), destination_.c_str()) != 0)
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

  std::string path_;         // as the caller named it, for errors
  std::string destination_;  // symbolic links resolved
  std::string temporary_;
  std::FILE* file_ = nullptr;
  bool renamed_ = false;
};

StagedFiles::StagedFiles() = default;
StagedFiles::~StagedFiles() = default;

std::FILE* StagedFiles::stage(const std::string& path) {
  prepare_output_file(path);
  temporaries_.push_back(std::make_unique<TemporaryFile>(path, resolve_symlinks(path)));
  return temporaries_.back()->file();
}

void StagedFiles::commit() {
  for (const auto& temporary : temporaries_) temporary->flush();
  std::vector<Backup> backups;
  const auto undo = [&] {
    for (std::size_t i = backups.size(); i-- > 0;)
      restore(temporaries_[i]->destination(), backups[i]);
  };
  for (const auto& temporary : temporaries_) {
    try {
      backups.push_back(keep_previous(temporary->destination(), temporary->path()));
    } catch (const FileError&) {
      undo();
      throw;
    }
    try {
      temporary->rename();
    } catch (const FileError&) {
      drop_unused(temporary->destination(), backups.back());
      backups.pop_back();
      undo();
      throw;
    }
  }
  for (const Backup& backup : backups)
    if (!backup.path.empty()) ::unlink(backup.path.c_str());
  // The renames reach the disk with their directories.
  for (const auto& temporary : temporaries_)
    sync_directory(directory_of(temporary->destination()), temporary->path());
  temporaries_.clear();
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
