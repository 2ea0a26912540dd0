#include "core/file_io.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "binbow/error.h"

namespace binbow::detail {

namespace {
std::string errno_text() {
  return std::strerror(errno);
}
}  // namespace

MappedFile::MappedFile(const std::string& path, bool populate) : path_(path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
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

void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write) {
  std::string temp = path + ".tmp-XXXXXX";
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) throw FileError(path, "cannot create a temporary file beside it: " + errno_text());
  std::FILE* file = ::fdopen(fd, "wb");
  if (file == nullptr) {
    ::close(fd);
    ::unlink(temp.c_str());
    throw FileError(path, "cannot open a temporary file: " + errno_text());
  }
  try {
    write(file);
    if (std::fflush(file) != 0) throw FileError(path, "cannot write: " + errno_text());
  } catch (...) {
    std::fclose(file);
    ::unlink(temp.c_str());
    throw;
  }
  // mkstemp creates 0600; give the file the permissions the user's umask asks for.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  if (std::fclose(file) != 0) {
    ::unlink(temp.c_str());
    throw FileError(path, "cannot write: " + errno_text());
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string why = errno_text();
    ::unlink(temp.c_str());
    throw FileError(path, "cannot replace the file: " + why);
  }
}

void write_file_atomically(const std::string& path, const void* data, std::size_t size) {
  write_file_atomically(path, [&](std::FILE* file) { write_all(file, data, size, path); });
}

}  // namespace binbow::detail
