// Vocabularies shipped compressed: any format may come gzip-compressed
// (ORBvoc.txt.gz) and, inside the gzip, as the first file of a tar archive
// (ORB-SLAM ships Vocabulary/ORBvoc.txt.tar.gz).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace binbow::detail {

struct ContainedFile {
  std::vector<std::uint8_t> storage;   // the decompressed bytes, when compressed
  const std::uint8_t* data = nullptr;  // the vocabulary file itself
  std::size_t size = 0;
  bool gzip = false;
  bool tar = false;
};

// Finds the vocabulary in `data`: itself, or the content of a gzip file, or
// of the first regular file of a tar archive in it. Throws FileError(name, ...)
// for corrupt or oversized gzip data and malformed tar headers.
ContainedFile open_contained(const std::uint8_t* data, std::size_t size, const std::string& name);

// The first regular file of a tar archive: offset and size in `data`. Returns
// false when `data` is not a tar archive; throws FileError when it is a
// malformed one or holds no file. With `partial`, `data` may be just the
// start of the archive and the member may extend beyond it.
bool find_tar_member(const std::uint8_t* data, std::size_t size, const std::string& name,
                     bool partial, std::size_t& offset, std::size_t& member_size);

// Enough of the start of what open_contained would return to recognise the
// format (the whole file when it is not compressed). `contained_size` is the
// vocabulary file's size when known (0 otherwise).
std::vector<std::uint8_t> contained_head(const std::uint8_t* data, std::size_t size,
                                         std::size_t& contained_size);

}  // namespace binbow::detail
