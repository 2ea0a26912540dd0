#include "core/regular_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "binbow/error.h"
#include "core/file_io.h"

namespace binbow::detail {
namespace {

[[noreturn]] void throw_not_regular(const std::string& path, mode_t mode) {
  throw FileError(path, std::string("is ") + file_kind(mode) + ", not a regular file");
}

// Closes the descriptor on every path out of read_regular_file.
struct Descriptor {
  int fd;
  ~Descriptor() { ::close(fd); }
};

}  // namespace

void require_regular_file(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) {
    throw FileError(path, errno == ENOENT ? std::string("no such file")
                                          : std::string("cannot open: ") + std::strerror(errno));
  }
  if (!S_ISREG(status.st_mode)) throw_not_regular(path, status.st_mode);
}

std::string read_regular_file(const std::string& path, std::uint64_t max_bytes) {
  // Non-blocking, so that a FIFO put in place of the file cannot block the
  // open itself; fstat then checks what was actually opened.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    throw FileError(path, errno == ENOENT ? std::string("no such file")
                                          : std::string("cannot open: ") + std::strerror(errno));
  }
  const Descriptor descriptor{fd};
  struct stat status {};
  if (::fstat(fd, &status) != 0) throw FileError(path, std::strerror(errno));
  if (!S_ISREG(status.st_mode)) throw_not_regular(path, status.st_mode);
  const auto too_large = [&] {
    return FileError(path, "larger than the limit of " + std::to_string(max_bytes) + " bytes");
  };
  if (static_cast<std::uint64_t>(status.st_size) > max_bytes) throw too_large();
  std::string bytes(static_cast<std::size_t>(status.st_size), '\0');
  std::size_t filled = 0;
  for (;;) {
    // The file may have grown since fstat: read on until EOF, within the limit.
    if (filled == bytes.size()) {
      if (bytes.size() >= max_bytes) {
        char probe;
        const ssize_t extra = ::read(fd, &probe, 1);
        if (extra > 0) throw too_large();
        if (extra == 0) break;
        if (errno == EINTR) continue;
        throw FileError(path, std::string("read error: ") + std::strerror(errno));
      }
      bytes.resize(static_cast<std::size_t>(
          std::min<std::uint64_t>(max_bytes, std::uint64_t{bytes.size()} * 2 + 4096)));
    }
    const ssize_t got = ::read(fd, &bytes[filled], bytes.size() - filled);
    if (got == 0) break;
    if (got < 0) {
      if (errno == EINTR) continue;
      throw FileError(path, std::string("read error: ") + std::strerror(errno));
    }
    filled += static_cast<std::size_t>(got);
  }
  bytes.resize(filled);
  return bytes;
}

}  // namespace binbow::detail
