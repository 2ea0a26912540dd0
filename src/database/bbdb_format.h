// binbow's database format (.bbdb), shared by its writer (database_save.cpp)
// and its reader (database_load.cpp). Layout, all little-endian:
//   header (64 bytes, CRC32C in its last 4), section table (24 bytes per
//   section: id, CRC32C, offset, length; then the table's CRC32C), then the
//   sections back to back in id order up to the end of the file, so that
//   every byte is covered by a CRC. Sections, always present (maybe empty):
//   1 embedded .bbw vocabulary   2 vocabulary description (text)
//   3 entry states (u8 per id)
//   Version 3 (written): the index in parts of 65,536 ids (part k holds the
//   postings of ids [65,536 k, 65,536 (k + 1))), each part's rows exactly
//   the bytes a database keeps in memory:
//   4 parts (per part: u32 rows, u32 postings)
//   5 rows (per part, per word with postings: u32 word, u32 bytes), by
//     word mod 65,536, then word / 65,536
//   6 postings, by part, row: the row's header (u8: its gap width, 1 if
//     every gap of the row is below 256, else 2; plus 16 for a count row),
//     then by id per posting the gap from the row's previous id minus 1
//     (the first: id - the part's first id; u8 or u16 by the width), then
//     its weight (f32), or in a count row its count (u8, ≥ 1): the weight
//     is then float(word weight * count / divisor), in doubles
//   7 divisors (f64 per id: > 0 for an entry whose weights are its counts'
//     as above, which count rows may hold; 0 for the others)
//   8 direct index sizes (per id: u32 nodes, u32 features, u32 bytes)
//   9 direct index data (per live entry: u8 layout, u32 bytes of node ids,
//     the node ids as steps from the previous one (LEB128), then per
//     feature its node's position (u8, u16 or 7 bits packed from the low
//     bit of the first byte: layouts 0, 1, 4) or per node the end of its
//     features and the feature indices (u16 or u32: layouts 2, 3))
//   Version 2 (read): as version 3 without count rows, but 5 rows count
//   postings (u32 length),
//   6 holds their ids (u16: id - the part's first id), 7 their weights
//   (f32), and the direct index has no layout 4.
//   Version 1 (read): the index by word over every id:
//   4 words with postings (u32, increasing)  5 posting list lengths (u32)
//   6 posting entry ids (u32)  7 weights (f32)
//   8 direct index sizes (per id: u32 node count, u32 feature count)
//   9 direct index data (per entry: u32 nodes, node end offsets, feature indices)
//  10 label lengths (u32 per id)  11 label bytes
// Removed entries keep their id (state 0) and have no postings.
// A database over word ids (flag 4, Database::over_word_ids) has no
// vocabulary: its checksum (32) is 0, section 1 and 2 are empty, the scoring
// is at 36 (u32) and the word-id capacity of its index at 52 (u64).
#pragma once

#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "core/crc32c.h"
#include "core/file_io.h"
#include "core/little_endian.h"
#include "core/sectioned_file.h"
#include "database/database_impl.h"

namespace binbow::detail::bbdb {

inline constexpr char kMagic[8] = {'B', 'I', 'N', 'B', 'O', 'W', 'D', 'B'};
inline constexpr std::uint32_t kVersion = 3;  // written; versions 1 and 2 are read too
inline constexpr std::size_t kHeaderSize = detail::kSectionedHeaderSize;

enum Section : std::uint32_t {
  kVocabularyBytes = 0,
  kDescription,
  kEntryStates,
  kParts,           // version 1: kWords
  kRows,            // version 1: kListLengths
  kPostingEntries,  // version 1: kPostingIds; version 3: kPostingBytes
  kPostingWeights,  // version 3: kDivisors
  kDirectSizes,
  kDirectData,
  kLabelLengths,
  kLabelBytes,
  kSectionCount,
  kWords = kParts,
  kListLengths = kRows,
  kPostingIds = kPostingEntries,
  kPostingBytes = kPostingEntries,
  kDivisors = kPostingWeights,
};

inline constexpr const char* kSectionNames[kSectionCount] = {
    "vocabulary",   "vocabulary description", "entry states",    "parts",
    "rows",         "posting entries",        "posting weights", "direct index sizes",
    "direct index", "label lengths",          "labels"};
inline constexpr const char* kVersion3SectionNames[kSectionCount] = {
    "vocabulary", "vocabulary description", "entry states", "parts",         "rows",  "postings",
    "divisors",   "direct index sizes",     "direct index", "label lengths", "labels"};
inline constexpr const char* kVersion1SectionNames[kSectionCount] = {
    "vocabulary",  "vocabulary description", "entry states",       "words",        "list lengths",
    "posting ids", "posting weights",        "direct index sizes", "direct index", "label lengths",
    "labels"};

inline constexpr std::uint32_t kFlagDirectIndex = 1;
inline constexpr std::uint32_t kFlagVocabulary = 2;
inline constexpr std::uint32_t kFlagOverWordIds = 4;
// The word-id capacity an over-word-ids database starts with and the most it
// can reach (Database::Impl::grow_words).
inline constexpr std::uint64_t kMaxWordCapacity = std::uint64_t{1} << 32;

// The largest word-id capacity an over-word-ids index reaches when its
// largest word id is `word_end` - 1: growth takes max(needed, twice the
// capacity), starting at kInitialWordCapacity.
inline std::uint64_t largest_capacity(std::uint64_t word_end) {
  return std::clamp<std::uint64_t>(2 * word_end, detail::kInitialWordCapacity, kMaxWordCapacity);
}

struct Header {
  std::uint32_t version = 0;
  EntryId next_entry_id = 0;
  std::uint32_t live_entries = 0;
  std::uint32_t flags = 0;
  std::uint32_t levels_up = 0;
  std::uint32_t vocabulary_checksum = 0;
  std::uint64_t postings = 0;
  Scoring scoring = Scoring::kL1;   // over word ids only
  std::uint64_t word_capacity = 0;  // over word ids only
  bool over_word_ids() const { return (flags & kFlagOverWordIds) != 0; }
};

// Header, table and section bounds of a .bbdb image, all checked. Section
// CRCs are checked for every section with `verify_all`, else only for those
// verified explicitly (inspect() without verification reads a few).
class Layout {
 public:
  Layout(const std::uint8_t* data, std::size_t size, const std::string& name, bool verify_all)
      : name_(name), size_(size) {
    if (size < kHeaderSize)
      fail("truncated: " + std::to_string(size) + " bytes, shorter than the " +
           std::to_string(kHeaderSize) + "-byte header of a .bbdb database");
    if (std::memcmp(data, kMagic, 8) != 0) fail("not a binbow database (.bbdb): wrong magic bytes");
    header_.version = detail::load_le<std::uint32_t>(data + 8);
    if (header_.version < 1 || header_.version > kVersion)
      fail("unsupported .bbdb format version " + std::to_string(header_.version) +
           " (this binbow reads versions 1 to " + std::to_string(kVersion) +
           "): saved by a newer binbow?");
    names_ = header_.version == 1   ? kVersion1SectionNames
             : header_.version == 2 ? kSectionNames
                                    : kVersion3SectionNames;
    if (detail::load_le<std::uint32_t>(data + 60) != detail::crc32c(data, 60))
      fail("header checksum mismatch: the file is corrupted");
    if (detail::load_le<std::uint32_t>(data + 12) != kHeaderSize) fail("unexpected header size");
    header_.next_entry_id = detail::load_le<std::uint32_t>(data + 16);
    header_.live_entries = detail::load_le<std::uint32_t>(data + 20);
    header_.flags = detail::load_le<std::uint32_t>(data + 24);
    header_.levels_up = detail::load_le<std::uint32_t>(data + 28);
    header_.vocabulary_checksum = detail::load_le<std::uint32_t>(data + 32);
    header_.postings = detail::load_le<std::uint64_t>(data + 40);
    const auto section_count = detail::load_le<std::uint32_t>(data + 48);
    if (header_.flags > (kFlagDirectIndex | kFlagVocabulary | kFlagOverWordIds))
      fail("unknown flags " + std::to_string(header_.flags));
    if (header_.over_word_ids()) {
      const auto scoring = detail::load_le<std::uint32_t>(data + 36);
      if ((header_.flags & kFlagVocabulary) != 0 || header_.vocabulary_checksum != 0 ||
          scoring > static_cast<std::uint32_t>(Scoring::kDotProduct))
        fail("inconsistent header of a database over word ids");
      header_.scoring = static_cast<Scoring>(scoring);
      header_.word_capacity = detail::load_le<std::uint64_t>(data + 52);
    }
    if (header_.levels_up > kMaxDirectIndexLevelsUp)
      fail("direct index level " + std::to_string(header_.levels_up) + " is out of range");
    if (header_.live_entries > header_.next_entry_id || header_.next_entry_id == kAllEntries)
      fail("inconsistent entry counts in the header");
    if (section_count != kSectionCount)
      fail("expected " + std::to_string(kSectionCount) + " sections, the header says " +
           std::to_string(section_count));

    const std::vector<detail::Section> sections = detail::read_section_table(
        data, size, kSectionCount, names_, [this](const std::string& p) { fail(p); });
    std::copy(sections.begin(), sections.end(), sections_);
    if (verify_all)
      for (std::uint32_t i = 0; i < kSectionCount; ++i) verify(static_cast<Section>(i));
  }

  [[noreturn]] void fail(const std::string& problem) const { throw FileError(name_, problem); }
  const std::string& name() const { return name_; }
  const Header& header() const { return header_; }
  std::size_t file_size() const { return size_; }
  const detail::Section& section(Section s) const { return sections_[s]; }
  void verify(Section s) const {
    if (!detail::section_intact(sections_[s]))
      fail(std::string("checksum mismatch in section '") + names_[s] + "': the file is corrupted");
  }
  // The section as `count` values of T, its CRC checked; fails unless its
  // length is exactly that.
  template <class T>
  std::vector<T> values(Section s, std::size_t count) const {
    const std::uint8_t* data = array(s, count, sizeof(T));
    std::vector<T> out(count);
    if (count > 0) std::memcpy(out.data(), data, count * sizeof(T));
    return out;
  }
  // The same, in place (little-endian values, maybe unaligned).
  const std::uint8_t* array(Section s, std::size_t count, std::size_t value_size) const {
    if (sections_[s].size / value_size != count || sections_[s].size % value_size != 0)
      fail(std::string("section '") + names_[s] + "' has " + std::to_string(sections_[s].size) +
           " bytes, expected " + std::to_string(count * value_size));
    verify(s);
    return sections_[s].data;
  }
  std::size_t count_of(Section s, std::size_t value_size) const {
    if (sections_[s].size % value_size != 0)
      fail(std::string("section '") + names_[s] + "' has a length that is not a multiple of " +
           std::to_string(value_size));
    return sections_[s].size / value_size;
  }

 private:
  std::string name_;
  std::size_t size_;
  Header header_;
  const char* const* names_ = kSectionNames;
  detail::Section sections_[kSectionCount];
};

// Told when the reader is done with a section of the file.
using Release = std::function<void(const std::uint8_t* data, std::size_t size)>;

// Where a reader's bytes come from. With `file` (load), the large sections
// of a version 3 file (the rows, the direct index) stay in it as the
// database's storage, and are checked by a BackgroundCheck, on a thread of
// its own if `background`; without (deserialize: a caller's buffer), they
// are copied, and checked before the reader returns.
struct Source {
  Release release;
  std::shared_ptr<const detail::MappedFile> file;
  bool background = false;
};

}  // namespace binbow::detail::bbdb
