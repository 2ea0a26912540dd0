// The streaming writer of the sectioned container (.bbdb) writes exactly the
// bytes of the in-memory one, whatever the sizes of the sections and of the
// pieces they are appended in.
#include "core/sectioned_file.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

namespace binbow::detail {
namespace {

TEST(SectionedFileWriter, WritesTheBytesOfTheInMemoryWriter) {
  // Sections larger than the writer's 1 MiB buffer, empty ones, tiny ones.
  const std::size_t sizes[] = {0, 3, (std::size_t{5} << 20) + 17, 0, 1000, (std::size_t{1} << 20)};
  std::mt19937_64 rng(5);
  std::vector<std::vector<std::uint8_t>> sections;
  for (std::size_t size : sizes) {
    std::vector<std::uint8_t> section(size);
    for (auto& byte : section) byte = static_cast<std::uint8_t>(rng());
    sections.push_back(std::move(section));
  }
  const auto count = static_cast<std::uint32_t>(sections.size());
  const auto fill_header = [](std::uint8_t* header) { store_le<std::uint32_t>(header + 16, 42); };
  const std::vector<std::uint8_t> expected =
      write_sectioned_file("TESTFILE", 7, sections.data(), count, fill_header);

  std::vector<std::uint8_t> streamed;
  std::size_t header_writes = 0;
  SectionedFileWriter writer(count,
                             [&](std::size_t offset, const std::uint8_t* data, std::size_t size) {
                               if (offset == 0) ++header_writes;
                               if (streamed.size() < offset + size) streamed.resize(offset + size);
                               std::memcpy(streamed.data() + offset, data, size);
                             });
  for (std::uint32_t i = 0; i < count; ++i) {
    if (i > 0) writer.next_section();
    // Pieces of varying sizes, and values through append_le.
    std::size_t at = 0;
    while (at < sections[i].size()) {
      if (sections[i].size() - at >= 4 && at % 3 == 0) {
        writer.append_le<std::uint32_t>(load_le<std::uint32_t>(sections[i].data() + at));
        at += 4;
        continue;
      }
      const std::size_t piece = std::min<std::size_t>(rng() % 300000 + 1, sections[i].size() - at);
      writer.append(sections[i].data() + at, piece);
      at += piece;
    }
  }
  writer.finish("TESTFILE", 7, fill_header);
  EXPECT_EQ(header_writes, 1u);
  EXPECT_EQ(streamed, expected);
}

}  // namespace
}  // namespace binbow::detail
