#include "formats/container.h"

#include <cstring>

#include "binbow/error.h"
#include "formats/gzip.h"

namespace binbow::detail {

namespace {

constexpr std::size_t kTarBlock = 512;
constexpr std::size_t kHeadBytes = 4096;

bool is_tar_header(const std::uint8_t* block) {
  return std::memcmp(block + 257, "ustar", 5) == 0;
}

// A tar size field: octal digits, padded with NUL or blanks.
bool parse_tar_size(const std::uint8_t* field, std::size_t& size) {
  size = 0;
  std::size_t i = 0;
  while (i < 12 && field[i] == ' ') ++i;
  std::size_t digits = 0;
  for (; i < 12 && field[i] >= '0' && field[i] <= '7'; ++i, ++digits) {
    if (size > (SIZE_MAX >> 3)) return false;
    size = size * 8 + (field[i] - '0');
  }
  for (; i < 12; ++i)
    if (field[i] != 0 && field[i] != ' ') return false;
  return digits > 0;
}

}  // namespace

bool find_tar_member(const std::uint8_t* data, std::size_t size, const std::string& name,
                     bool partial, std::size_t& offset, std::size_t& member_size) {
  if (size < kTarBlock || !is_tar_header(data)) return false;
  for (std::size_t at = 0; at + kTarBlock <= size;) {
    const std::uint8_t* header = data + at;
    if (header[0] == 0) break;  // end-of-archive blocks
    if (!is_tar_header(header))
      throw FileError(name, "malformed tar archive: bad header at offset " + std::to_string(at));
    std::size_t entry_size = 0;
    if (!parse_tar_size(header + 124, entry_size))
      throw FileError(name,
                      "malformed tar archive: bad size field at offset " + std::to_string(at));
    const std::size_t content = at + kTarBlock;
    const char type = static_cast<char>(header[156]);
    const bool regular = type == '0' || type == '\0';
    if (entry_size > size - content && !(partial && regular))
      throw FileError(name, "truncated tar archive: a member of " + std::to_string(entry_size) +
                                " bytes does not fit");
    if (regular) {
      offset = content;
      member_size = entry_size;
      return true;
    }
    // Directories, links, long-name and pax records: skip.
    at = content + (entry_size + kTarBlock - 1) / kTarBlock * kTarBlock;
  }
  throw FileError(name, "the tar archive holds no regular file");
}

ContainedFile open_contained(const std::uint8_t* data, std::size_t size, const std::string& name) {
  ContainedFile file;
  file.data = data;
  file.size = size;
  if (!is_gzip(data, size)) return file;
  file.gzip = true;
  file.storage = gunzip(data, size, name, gunzip_limit(size));
  file.data = file.storage.data();
  file.size = file.storage.size();
  std::size_t offset = 0, member_size = 0;
  if (find_tar_member(file.data, file.size, name, false, offset, member_size)) {
    file.tar = true;
    file.data += offset;
    file.size = member_size;
  }
  if (file.size == 0) throw FileError(name, "the compressed file is empty");
  return file;
}

std::vector<std::uint8_t> contained_head(const std::uint8_t* data, std::size_t size,
                                         std::size_t& contained_size) {
  contained_size = size;
  if (!is_gzip(data, size))
    return std::vector<std::uint8_t>(data, data + std::min(size, kHeadBytes));
  contained_size = 0;
  std::vector<std::uint8_t> head = gunzip_head(data, size, 4 * kTarBlock + kHeadBytes);
  std::size_t offset = 0, member_size = 0;
  try {
    if (find_tar_member(head.data(), head.size(), "", true, offset, member_size)) {
      contained_size = member_size;
      head.erase(head.begin(), head.begin() + static_cast<std::ptrdiff_t>(offset));
    }
  } catch (const FileError&) {
    // Unrecognisable from its start; the full load reports the problem.
  }
  return head;
}

}  // namespace binbow::detail
