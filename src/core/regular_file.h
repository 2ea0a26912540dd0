// Reading the files binbow is handed by name. Only regular files are read: a
// FIFO or a terminal would block forever and a device may never end, so
// they are refused before any byte is read.
#pragma once

#include <cstdint>
#include <string>

namespace binbow::detail {

// Throws FileError naming `path` unless it is a regular file (symbolic links
// followed): missing, a directory, a FIFO, a socket or a device.
void require_regular_file(const std::string& path);

// The whole content of the regular file `path`. Throws FileError naming it
// when it is not a regular file (as above), cannot be read, or holds more
// than `max_bytes` bytes (the message gives the limit).
std::string read_regular_file(const std::string& path, std::uint64_t max_bytes);

}  // namespace binbow::detail
