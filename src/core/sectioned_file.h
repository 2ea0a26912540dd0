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

#include "core/little_endian.h"

namespace binbow::detail {

inline constexpr std::size_t kSectionedHeaderSize = 64;
inline constexpr std::size_t kSectionEntrySize = 24;

// The file image of `count` sections; `magic` is 8 bytes. `fill_header` writes the format's
// fields into bytes 16..59 of the header (the section count at 48 is
// written already); the header CRC is computed after it.
std::vector<std::uint8_t> write_sectioned_file(
    const char* magic, std::uint32_t version, const std::vector<std::uint8_t>* sections,
    std::uint32_t count, const std::function<void(std::uint8_t* header)>& fill_header);

// The same container, written section by section as the sections are
// produced, so that a large file never exists in memory: the space for the
// header and the table is kept at the start, each section's CRC32C is
// computed as its bytes pass, and finish() writes the header and the table
// last, at offset 0. The bytes are those write_sectioned_file() makes.
class SectionedFileWriter {
 public:
  // Receives the file's bytes: the sections in order, then the header and
  // table (offset 0); every other call continues where the previous ended.
  using Output =
      std::function<void(std::size_t offset, const std::uint8_t* data, std::size_t size)>;

  SectionedFileWriter(std::uint32_t count, Output output);
  // An Output that builds the file's image in `bytes` (which must outlive it).
  static Output into(std::vector<std::uint8_t>& bytes);
  // Appends to the current section; sections are written in id order,
  // starting with section 0.
  void append(const void* data, std::size_t size);
  template <class T>
  void append_le(T value) {
    if (buffer_.size() - used_ < sizeof(T)) flush();
    store_le<T>(buffer_.data() + used_, value);
    used_ += sizeof(T);
  }
  // Ends the current section; the next appends go to the following one.
  void next_section();
  // Ends the last section and writes the header and the table.
  void finish(const char* magic, std::uint32_t version,
              const std::function<void(std::uint8_t* header)>& fill_header);

 private:
  void flush();

  std::uint32_t count_;
  Output output_;
  std::vector<std::uint8_t> buffer_;
  std::size_t used_ = 0;
  std::size_t end_;  // file offset of the first byte not yet output
  std::uint32_t section_ = 0;
  std::vector<std::uint32_t> crcs_;
  std::vector<std::size_t> offsets_;
};

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
