// The container shared by .bbdb databases and .bbov online vocabularies: a
// 64-byte header (magic 0..7, version 8, header size 12, the format's own
// fields 16..59 with the section count at 48, CRC32C of bytes 0..59 at 60),
// a table of one 24-byte entry per section (id, CRC32C, offset, length) and
// its CRC32C, then the sections back to back. Little-endian throughout.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace binbow::detail {

inline constexpr std::size_t kSectionedHeaderSize = 64;
inline constexpr std::size_t kSectionEntrySize = 24;

// The file image of `count` sections; `magic` is 8 bytes. `fill_header` writes the format's
// fields into bytes 16..59 of the header (the section count at 48 is
// written already); the header CRC is computed after it.
std::vector<std::uint8_t> write_sectioned_file(
    const char* magic, std::uint32_t version, const std::vector<std::uint8_t>* sections,
    std::uint32_t count, const std::function<void(std::uint8_t* header)>& fill_header);

struct Section {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
  std::uint32_t crc = 0;  // as the table records it; see section_intact()
};

// The sections of a file image whose header was checked by the caller:
// the table's CRC, every entry's id, offset (sections back to back, in
// order) and length within the file, and nothing after the last one.
// Section CRCs are not checked here (section_intact), so that a reader can
// check only the sections it reads. Problems go to `fail` (which throws),
// naming the section by `names[i]`.
std::vector<Section> read_section_table(const std::uint8_t* data, std::size_t size,
                                        std::uint32_t count, const char* const* names,
                                        const std::function<void(const std::string&)>& fail);

bool section_intact(const Section& section);

}  // namespace binbow::detail
