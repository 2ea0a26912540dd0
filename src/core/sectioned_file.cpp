#include "core/sectioned_file.h"

#include <algorithm>
#include <cstring>
#include <utility>

#include "core/crc32c.h"
#include "core/little_endian.h"

namespace binbow::detail {

std::vector<std::uint8_t> write_sectioned_file(
    const char* magic, std::uint32_t version, const std::vector<std::uint8_t>* sections,
    std::uint32_t count, const std::function<void(std::uint8_t* header)>& fill_header) {
  std::size_t size = kSectionedHeaderSize + count * kSectionEntrySize + 4;
  for (std::uint32_t i = 0; i < count; ++i) size += sections[i].size();
  std::vector<std::uint8_t> out;
  out.reserve(size);
  SectionedFileWriter writer(count, SectionedFileWriter::into(out));
  for (std::uint32_t i = 0; i < count; ++i) {
    if (i > 0) writer.next_section();
    writer.append(sections[i].data(), sections[i].size());
  }
  writer.finish(magic, version, fill_header);
  return out;
}

SectionedFileWriter::Output SectionedFileWriter::into(std::vector<std::uint8_t>& bytes) {
  return [&bytes](std::size_t offset, const std::uint8_t* data, std::size_t size) {
    if (bytes.size() < offset + size) bytes.resize(offset + size);
    if (size > 0) std::memcpy(bytes.data() + offset, data, size);
  };
}

SectionedFileWriter::SectionedFileWriter(std::uint32_t count, Output output)
    : count_(count),
      output_(std::move(output)),
      buffer_(std::size_t{1} << 20),
      end_(kSectionedHeaderSize + count * kSectionEntrySize + 4),
      crcs_(count, 0),
      offsets_(count + 1, end_) {}

void SectionedFileWriter::flush() {
  if (used_ == 0) return;
  crcs_[section_] = crc32c(buffer_.data(), used_, crcs_[section_]);
  output_(end_, buffer_.data(), used_);
  end_ += used_;
  used_ = 0;
}

void SectionedFileWriter::append(const void* data, std::size_t size) {
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  while (size > 0) {
    if (used_ == buffer_.size()) flush();
    const std::size_t part = std::min(size, buffer_.size() - used_);
    std::memcpy(buffer_.data() + used_, bytes, part);
    used_ += part;
    bytes += part;
    size -= part;
  }
}

void SectionedFileWriter::next_section() {
  flush();
  offsets_[++section_] = end_;
}

void SectionedFileWriter::finish(const char* magic, std::uint32_t version,
                                 const std::function<void(std::uint8_t* header)>& fill_header) {
  flush();
  offsets_[count_] = end_;
  const std::size_t table_size = count_ * kSectionEntrySize;
  std::vector<std::uint8_t> head(kSectionedHeaderSize + table_size + 4, 0);
  std::uint8_t* header = head.data();
  std::memcpy(header, magic, 8);
  store_le<std::uint32_t>(header + 8, version);
  store_le<std::uint32_t>(header + 12, kSectionedHeaderSize);
  store_le<std::uint32_t>(header + 48, count_);
  fill_header(header);
  store_le<std::uint32_t>(header + 60, crc32c(header, 60));
  std::uint8_t* table = header + kSectionedHeaderSize;
  for (std::uint32_t i = 0; i < count_; ++i) {
    std::uint8_t* entry = table + i * kSectionEntrySize;
    store_le<std::uint32_t>(entry, i);
    store_le<std::uint32_t>(entry + 4, crcs_[i]);
    store_le<std::uint64_t>(entry + 8, offsets_[i]);
    store_le<std::uint64_t>(entry + 16, offsets_[i + 1] - offsets_[i]);
  }
  store_le<std::uint32_t>(table + table_size, crc32c(table, table_size));
  output_(0, head.data(), head.size());
}

std::vector<Section> read_section_table(const std::uint8_t* data, std::size_t size,
                                        std::uint32_t count, const char* const* names,
                                        const std::function<void(const std::string&)>& fail) {
  const std::size_t table_size = count * kSectionEntrySize;
  if (size < kSectionedHeaderSize + table_size + 4) fail("truncated inside the section table");
  const std::uint8_t* table = data + kSectionedHeaderSize;
  if (load_le<std::uint32_t>(table + table_size) != crc32c(table, table_size))
    fail("section table checksum mismatch: the file is corrupted");
  std::vector<Section> sections(count);
  std::size_t expected_offset = kSectionedHeaderSize + table_size + 4;
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::uint8_t* entry = table + i * kSectionEntrySize;
    const auto id = load_le<std::uint32_t>(entry);
    const auto offset = load_le<std::uint64_t>(entry + 8);
    const auto length = load_le<std::uint64_t>(entry + 16);
    const std::string section = std::string("section '") + names[i] + "'";
    if (id != i) fail("unexpected section id " + std::to_string(id));
    if (offset != expected_offset) fail(section + " is not where the table says");
    if (offset > size || length > size - offset)
      fail(section + " lies outside the file (truncated?)");
    sections[i] = {data + offset, static_cast<std::size_t>(length),
                   load_le<std::uint32_t>(entry + 4)};
    expected_offset += length;
  }
  if (expected_offset != size)
    fail(std::to_string(size - expected_offset) + " unexpected bytes after the last section");
  return sections;
}

bool section_intact(const Section& section) {
  return crc32c(section.data, section.size) == section.crc;
}

}  // namespace binbow::detail
