// binbow's database format (.bbdb). Layout, all little-endian:
//   header (64 bytes, CRC32C in its last 4), section table (24 bytes per
//   section: id, CRC32C, offset, length; then the table's CRC32C), then the
//   sections back to back in id order up to the end of the file, so that
//   every byte is covered by a CRC. Sections, always present (maybe empty):
//   1 embedded .bbw vocabulary   2 vocabulary description (text)
//   3 entry states (u8 per id)   4 words with postings (u32, increasing)
//   5 posting list lengths (u32) 6 posting entry ids (u32)  7 weights (f32)
//   8 direct index sizes (u32 node count, u32 feature count per id)
//   9 direct index data (per entry: nodes, node end offsets, feature indices)
//  10 label lengths (u32 per id)  11 label bytes
// Removed entries keep their id (state 0) and have no postings.
// A database over word ids (flag 4, Database::over_word_ids) has no
// vocabulary: its checksum (32) is 0, section 1 and 2 are empty, the scoring
// is at 36 (u32) and the word-id capacity of its index at 52 (u64).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "core/crc32c.h"
#include "core/database_impl.h"
#include "core/file_io.h"
#include "core/little_endian.h"
#include "core/sectioned_file.h"

namespace binbow {

namespace {

constexpr char kMagic[8] = {'B', 'I', 'N', 'B', 'O', 'W', 'D', 'B'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderSize = detail::kSectionedHeaderSize;

enum Section : std::uint32_t {
  kVocabularyBytes = 0,
  kDescription,
  kEntryStates,
  kWords,
  kListLengths,
  kPostingIds,
  kPostingWeights,
  kDirectSizes,
  kDirectData,
  kLabelLengths,
  kLabelBytes,
  kSectionCount,
};

constexpr const char* kSectionNames[kSectionCount] = {
    "vocabulary",  "vocabulary description", "entry states",       "words",        "list lengths",
    "posting ids", "posting weights",        "direct index sizes", "direct index", "label lengths",
    "labels"};

constexpr std::uint32_t kFlagDirectIndex = 1;
constexpr std::uint32_t kFlagVocabulary = 2;
constexpr std::uint32_t kFlagOverWordIds = 4;
// The word-id capacity an over-word-ids database starts with and the most it
// can reach (Database::Impl::grow_words).
constexpr std::uint64_t kMaxWordCapacity = std::uint64_t{1} << 32;

// The largest word-id capacity an over-word-ids index reaches when its
// largest word id is `word_end` - 1: growth takes max(needed, twice the
// capacity), starting at kInitialWordCapacity.
std::uint64_t largest_capacity(std::uint64_t word_end) {
  return std::clamp<std::uint64_t>(2 * word_end, detail::kInitialWordCapacity, kMaxWordCapacity);
}

template <class T>
void append_values(std::vector<std::uint8_t>& out, const T* values, std::size_t count) {
  const std::size_t at = out.size();
  out.resize(at + count * sizeof(T));
  if (count > 0) std::memcpy(out.data() + at, values, count * sizeof(T));
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
    if (header_.version != kVersion)
      fail("unsupported .bbdb format version " + std::to_string(header_.version) +
           " (this binbow reads version " + std::to_string(kVersion) + ")");
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
        data, size, kSectionCount, kSectionNames, [this](const std::string& p) { fail(p); });
    std::copy(sections.begin(), sections.end(), sections_);
    if (verify_all)
      for (std::uint32_t i = 0; i < kSectionCount; ++i) verify(static_cast<Section>(i));
  }

  [[noreturn]] void fail(const std::string& problem) const { throw FileError(name_, problem); }
  const Header& header() const { return header_; }
  std::size_t file_size() const { return size_; }
  const detail::Section& section(Section s) const { return sections_[s]; }
  void verify(Section s) const {
    if (!detail::section_intact(sections_[s]))
      fail(std::string("checksum mismatch in section '") + kSectionNames[s] +
           "': the file is corrupted");
  }
  // The section as `count` values of T; fails unless its length is exactly that.
  template <class T>
  std::vector<T> values(Section s, std::size_t count) const {
    if (sections_[s].size / sizeof(T) != count || sections_[s].size % sizeof(T) != 0)
      fail(std::string("section '") + kSectionNames[s] + "' has " +
           std::to_string(sections_[s].size) + " bytes, expected " +
           std::to_string(count * sizeof(T)));
    std::vector<T> out(count);
    if (count > 0) std::memcpy(out.data(), sections_[s].data, count * sizeof(T));
    return out;
  }
  std::size_t count_of(Section s, std::size_t value_size) const {
    if (sections_[s].size % value_size != 0)
      fail(std::string("section '") + kSectionNames[s] +
           "' has a length that is not a multiple of " + std::to_string(value_size));
    return sections_[s].size / value_size;
  }

 private:
  std::string name_;
  std::size_t size_;
  Header header_;
  detail::Section sections_[kSectionCount];
};

}  // namespace

std::vector<std::uint8_t> Database::serialize(bool include_vocabulary) const {
  std::shared_lock lock(impl_->mutex);
  const Impl& impl = *impl_;
  include_vocabulary = include_vocabulary && !impl.over_word_ids;
  const auto next_id = static_cast<EntryId>(impl.alive.size());
  std::vector<std::uint8_t> sections[kSectionCount];
  if (include_vocabulary) sections[kVocabularyBytes] = impl.vocabulary.serialize();
  const std::string description = impl.vocabulary.description();
  if (!impl.over_word_ids) sections[kDescription].assign(description.begin(), description.end());
  sections[kEntryStates] = impl.alive;

  // Live postings only, words in increasing order.
  std::uint64_t posting_count = 0;
  const std::size_t word_count = impl.word_capacity;
  std::uint64_t largest_word_end = 0;  // 1 + the largest word with a posting
  for (WordId word = 0; word < word_count; ++word) {
    // Segments first, oldest first, then the tail: entry ids increase.
    const detail::TailList list = impl.tail_lists[detail::group_of(word)];
    const std::uint32_t high_mask = (1u << impl.high_bits) - 1;
    const detail::TailPosting* tail = list.size != 0 ? impl.arena.at(list.block) : nullptr;
    const auto in_tail = [&](std::uint32_t i) {
      return (tail[i].key & high_mask) == word >> detail::kGroupBits;
    };
    const auto tail_entry = [&](std::uint32_t i) {
      return static_cast<EntryId>(impl.tail_first_entry + (tail[i].key >> impl.high_bits));
    };
    std::uint32_t live = 0;
    const std::uint32_t row = impl.row_order.row(word);
    for (const auto& segment : impl.segments)
      for (std::uint32_t i = segment->offsets[row]; i < segment->offsets[row + 1]; ++i)
        live += impl.alive[segment->entry(i)];
    for (std::uint32_t i = 0; i < list.size; ++i)
      if (in_tail(i)) live += impl.alive[tail_entry(i)];
    if (live == 0) continue;
    largest_word_end = std::uint64_t{word} + 1;
    detail::put_le<std::uint32_t>(sections[kWords], word);
    detail::put_le<std::uint32_t>(sections[kListLengths], live);
    const auto put_posting = [&](EntryId entry, float weight) {
      if (impl.alive[entry] == 0) return;
      detail::put_le<std::uint32_t>(sections[kPostingIds], entry);
      detail::put_le<float>(sections[kPostingWeights], weight);
    };
    for (const auto& segment : impl.segments)
      for (std::uint32_t i = segment->offsets[row]; i < segment->offsets[row + 1]; ++i)
        put_posting(segment->entry(i), segment->weights.data()[i]);
    for (std::uint32_t i = 0; i < list.size; ++i)
      if (in_tail(i)) put_posting(tail_entry(i), tail[i].weight);
    posting_count += live;
  }

  if (impl.options.direct_index) {
    for (EntryId entry = 0; entry < next_id; ++entry) {
      if (impl.alive[entry] == 0) {
        detail::put_le<std::uint32_t>(sections[kDirectSizes], 0);
        detail::put_le<std::uint32_t>(sections[kDirectSizes], 0);
        continue;
      }
      const FeatureVector features = impl.direct[entry].unpack();
      detail::put_le<std::uint32_t>(sections[kDirectSizes],
                                    static_cast<std::uint32_t>(features.size()));
      detail::put_le<std::uint32_t>(sections[kDirectSizes],
                                    static_cast<std::uint32_t>(features.feature_count()));
      append_values(sections[kDirectData], features.nodes().data(), features.size());
      append_values(sections[kDirectData], features.offsets().data() + 1, features.size());
      append_values(sections[kDirectData], features.feature_indices().data(),
                    features.feature_count());
    }
  }

  if (!impl.labels.empty()) {
    for (EntryId entry = 0; entry < next_id; ++entry) {
      const std::string& label = impl.labels[entry];
      detail::put_le<std::uint32_t>(sections[kLabelLengths],
                                    static_cast<std::uint32_t>(label.size()));
      sections[kLabelBytes].insert(sections[kLabelBytes].end(), label.begin(), label.end());
    }
  }

  return detail::write_sectioned_file(
      kMagic, kVersion, sections, kSectionCount, [&](std::uint8_t* h) {
        detail::store_le<std::uint32_t>(h + 16, next_id);
        detail::store_le<std::uint32_t>(h + 20, static_cast<std::uint32_t>(impl.live_entries));
        detail::store_le<std::uint32_t>(h + 24, (impl.options.direct_index ? kFlagDirectIndex : 0) |
                                                    (include_vocabulary ? kFlagVocabulary : 0) |
                                                    (impl.over_word_ids ? kFlagOverWordIds : 0));
        detail::store_le<std::uint32_t>(h + 28, impl.options.direct_index_levels_up);
        detail::store_le<std::uint64_t>(h + 40, posting_count);
        if (!impl.over_word_ids) {
          detail::store_le<std::uint32_t>(h + 32, impl.vocabulary.checksum());
          return;
        }
        detail::store_le<std::uint32_t>(h + 36, static_cast<std::uint32_t>(impl.scoring));
        // Within what the postings justify (largest_capacity), which the
        // capacity exceeds only when the entries with the largest words were
        // removed: the index keeps its shape, and a reader can bound it.
        detail::store_le<std::uint64_t>(
            h + 52,
            std::min<std::uint64_t>(impl.word_capacity, largest_capacity(largest_word_end)));
      });
}

namespace {

std::string hex(std::uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof text, "%08x", value);
  return text;
}

// Every count below is checked against the length of the section it comes
// from before anything is allocated, so a hostile file cannot make the
// reader allocate more than its own size justifies. `impl` is empty, laid
// out for the file's words; a template only so that it can name the private
// Database::Impl.
template <class DatabaseImpl>
void read_index(const Layout& layout, DatabaseImpl* impl) {
  const Header& header = layout.header();
  const std::size_t word_count = impl->word_capacity;
  const std::uint64_t node_count =
      impl->over_word_ids ? kMaxWordCapacity : impl->vocabulary.node_count();
  const EntryId next_id = header.next_entry_id;

  impl->alive = layout.values<std::uint8_t>(kEntryStates, next_id);
  std::size_t live = 0;
  for (std::uint8_t state : impl->alive) {
    if (state > 1) layout.fail("invalid entry state " + std::to_string(state));
    live += state;
  }
  if (live != header.live_entries)
    layout.fail("the header counts " + std::to_string(header.live_entries) +
                " entries, the entry states " + std::to_string(live));
  impl->live_entries = live;

  const std::size_t list_count = layout.count_of(kWords, 4);
  if (list_count > word_count)
    layout.fail("more posting lists (" + std::to_string(list_count) + ") than words (" +
                std::to_string(word_count) + ")");
  const auto words = layout.values<std::uint32_t>(kWords, list_count);
  const auto lengths = layout.values<std::uint32_t>(kListLengths, list_count);
  const std::size_t posting_count = layout.count_of(kPostingIds, 4);
  if (posting_count != header.postings)
    layout.fail("the header counts " + std::to_string(header.postings) + " postings, the index " +
                std::to_string(posting_count));
  auto ids = layout.values<std::uint32_t>(kPostingIds, posting_count);
  auto weights = layout.values<float>(kPostingWeights, posting_count);
  if (posting_count > std::numeric_limits<std::uint32_t>::max())
    layout.fail("more postings than this binbow supports (2^32)");
  impl->word_counts.assign(next_id, 0);
  auto segment = std::make_unique<detail::Segment>();
  std::vector<std::uint32_t>& row_ends = segment->offsets;
  row_ends.assign(word_count + 1, 0);
  std::size_t at = 0;
  for (std::size_t l = 0; l < list_count; ++l) {
    if (words[l] >= word_count || (l > 0 && words[l] <= words[l - 1]))
      layout.fail("posting list words are out of range or not increasing (word " +
                  std::to_string(words[l]) + ")");
    const std::uint32_t length = lengths[l];
    if (length == 0 || length > posting_count - at)
      layout.fail("posting list of word " + std::to_string(words[l]) + " has an invalid length");
    for (std::size_t i = at; i < at + length; ++i) {
      if (ids[i] >= next_id || impl->alive[ids[i]] == 0 || (i > at && ids[i] <= ids[i - 1]))
        layout.fail("posting list of word " + std::to_string(words[l]) +
                    " names a missing entry or is not in increasing order");
      if (!std::isfinite(weights[i]))
        layout.fail("posting list of word " + std::to_string(words[l]) +
                    " has a non-finite weight");
      ++impl->word_counts[ids[i]];
    }
    row_ends[impl->row_order.row(words[l]) + 1] = length;
    at += length;
  }
  if (at != posting_count) layout.fail("posting lists do not cover every posting");
  for (std::size_t r = 0; r < word_count; ++r) row_ends[r + 1] += row_ends[r];
  // Everything loaded is one wide segment: no tail, however many entries.
  if (posting_count > 0) {
    segment->end_entry = next_id;
    segment->level = detail::kLoadedLevel;
    segment->wide = true;
    segment->entries32.resize(posting_count);
    segment->weights.resize(posting_count);
    std::size_t from = 0;
    for (std::size_t l = 0; l < list_count; ++l) {
      const std::uint32_t to = row_ends[impl->row_order.row(words[l])];
      std::memcpy(segment->entries32.data() + to, ids.data() + from, lengths[l] * sizeof(EntryId));
      std::memcpy(segment->weights.data() + to, weights.data() + from, lengths[l] * sizeof(float));
      from += lengths[l];
    }
    impl->segments.push_back(std::move(segment));
  }
  impl->tail_first_entry = next_id;

  if (impl->options.direct_index) {
    const auto sizes = layout.values<std::uint32_t>(kDirectSizes, std::size_t{next_id} * 2);
    const detail::Section& direct_data = layout.section(kDirectData);
    const std::size_t available = layout.count_of(kDirectData, 4);
    impl->direct.resize(next_id);
    std::size_t cursor = 0;
    for (EntryId entry = 0; entry < next_id; ++entry) {
      const std::uint64_t nodes = sizes[2 * std::size_t{entry}];
      const std::uint64_t features = sizes[2 * std::size_t{entry} + 1];
      if (impl->alive[entry] == 0) {
        if (nodes != 0 || features != 0)
          layout.fail("removed entry " + std::to_string(entry) + " has a direct index");
        continue;
      }
      if (2 * nodes + features > available - cursor)
        layout.fail("direct index of entry " + std::to_string(entry) + " runs past its section");
      const auto read = [&](std::size_t count) {
        std::vector<std::uint32_t> values(count);
        if (count > 0) std::memcpy(values.data(), direct_data.data + cursor * 4, count * 4);
        cursor += count;
        return values;
      };
      std::vector<NodeId> node_ids = read(nodes);
      std::vector<std::uint32_t> offsets = read(nodes);
      offsets.insert(offsets.begin(), 0);
      std::vector<std::uint32_t> indices = read(features);
      if (!node_ids.empty() && node_ids.back() >= node_count)
        layout.fail("direct index of entry " + std::to_string(entry) +
                    " names a node outside the vocabulary");
      try {
        impl->direct[entry] = detail::PackedFeatureVector(FeatureVector::from_arrays(
            std::move(node_ids), std::move(offsets), std::move(indices)));
      } catch (const InvalidArgument& e) {
        layout.fail("direct index of entry " + std::to_string(entry) +
                    " is inconsistent: " + e.what());
      }
    }
    if (cursor != available) layout.fail("direct index section has trailing data");
  } else if (layout.section(kDirectSizes).size != 0 || layout.section(kDirectData).size != 0) {
    layout.fail("direct index present in a database saved without one");
  }

  if (layout.section(kLabelLengths).size != 0) {
    const auto label_lengths = layout.values<std::uint32_t>(kLabelLengths, next_id);
    const detail::Section& bytes = layout.section(kLabelBytes);
    impl->labels.resize(next_id);
    std::size_t cursor = 0;
    for (EntryId entry = 0; entry < next_id; ++entry) {
      if (label_lengths[entry] > bytes.size - cursor)
        layout.fail("label of entry " + std::to_string(entry) + " runs past its section");
      impl->labels[entry].assign(reinterpret_cast<const char*>(bytes.data) + cursor,
                                 label_lengths[entry]);
      cursor += label_lengths[entry];
    }
    if (cursor != bytes.size) layout.fail("labels section has trailing data");
  } else if (layout.section(kLabelBytes).size != 0) {
    layout.fail("label bytes without label lengths");
  }
}

DatabaseOptions options_of(const Header& header) {
  DatabaseOptions options;
  options.direct_index = (header.flags & kFlagDirectIndex) != 0;
  options.direct_index_levels_up = header.levels_up;
  return options;
}

}  // namespace

Database Database::deserialize(const std::uint8_t* data, std::size_t size, const std::string& name,
                               Vocabulary vocabulary) {
  const Layout layout(data, size, name, true);
  const Header& header = layout.header();
  if (header.over_word_ids())
    layout.fail(
        "the database is over word ids (an online vocabulary's) and has no vocabulary; load it "
        "without one");
  if (vocabulary.empty()) layout.fail("the vocabulary given to load the database is empty");
  if (vocabulary.checksum() != header.vocabulary_checksum)
    layout.fail("the database was built with a different vocabulary (checksum " +
                hex(header.vocabulary_checksum) + ", the given vocabulary has " +
                hex(vocabulary.checksum()) + ")");
  auto impl = std::make_unique<Impl>(std::move(vocabulary), options_of(header));
  read_index(layout, impl.get());
  return Database(std::move(impl));
}

namespace {

// A database over word ids: its capacity is checked against its words before
// the index is laid out for it.
template <class DatabaseImpl>
void read_word_id_index(const Layout& layout, DatabaseImpl* impl) {
  const Header& header = layout.header();
  const detail::Section& words = layout.section(kWords);
  const std::uint64_t word_end =
      words.size >= 4
          ? std::uint64_t{detail::load_le<std::uint32_t>(words.data + words.size - 4)} + 1
          : 0;
  // Rows cost 4 bytes per word id in memory: ids far sparser than the
  // postings that name them (16 bytes each in the file) are refused, so
  // that a small file cannot claim billions of rows.
  if (word_end > detail::kInitialWordCapacity + 4 * std::uint64_t{layout.file_size()})
    layout.fail("word ids up to " + std::to_string(word_end - 1) +
                " are too sparse for a file of " + std::to_string(layout.file_size()) + " bytes");
  if (header.word_capacity < std::max<std::uint64_t>(word_end, detail::kInitialWordCapacity) ||
      header.word_capacity > largest_capacity(word_end))
    layout.fail("word-id capacity " + std::to_string(header.word_capacity) +
                " does not fit its words (the largest ends at " + std::to_string(word_end) + ")");
  impl->lay_out(static_cast<std::size_t>(header.word_capacity));
  read_index(layout, impl);
}

}  // namespace

Database Database::deserialize(const std::uint8_t* data, std::size_t size,
                               const std::string& name) {
  const Layout layout(data, size, name, false);
  if (layout.header().over_word_ids()) {
    for (std::uint32_t i = 0; i < kSectionCount; ++i) layout.verify(static_cast<Section>(i));
    auto impl = std::make_unique<Impl>(layout.header().scoring, options_of(layout.header()));
    read_word_id_index(layout, impl.get());
    return Database(std::move(impl));
  }
  if ((layout.header().flags & kFlagVocabulary) == 0)
    layout.fail("the database does not include its vocabulary (checksum " +
                hex(layout.header().vocabulary_checksum) +
                "); load it together with the vocabulary it was built with");
  layout.verify(kVocabularyBytes);
  const detail::Section& bytes = layout.section(kVocabularyBytes);
  Vocabulary vocabulary = Vocabulary::deserialize(bytes.data, bytes.size, name + " (vocabulary)");
  return deserialize(data, size, name, std::move(vocabulary));
}

void Database::save(const std::string& path, bool include_vocabulary) const {
  const std::vector<std::uint8_t> bytes = serialize(include_vocabulary);
  detail::write_file_atomically(path, bytes.data(), bytes.size());
}

Database Database::load(const std::string& path) {
  const detail::MappedFile file(path);
  return deserialize(file.data(), file.size(), path);
}

Database Database::load(const std::string& path, Vocabulary vocabulary) {
  const detail::MappedFile file(path);
  return deserialize(file.data(), file.size(), path, std::move(vocabulary));
}

DatabaseFileInfo Database::inspect(const std::string& path, bool verify) {
  const detail::MappedFile file(path);
  const Layout layout(file.data(), file.size(), path, verify);
  if (verify && ((layout.header().flags & kFlagVocabulary) != 0 || layout.header().over_word_ids()))
    deserialize(file.data(), file.size(), path);
  layout.verify(kDescription);
  const Header& header = layout.header();
  DatabaseFileInfo info;
  info.version = header.version;
  info.entries = header.live_entries;
  info.next_entry_id = header.next_entry_id;
  info.direct_index = (header.flags & kFlagDirectIndex) != 0;
  info.direct_index_levels_up = header.levels_up;
  info.vocabulary_included = (header.flags & kFlagVocabulary) != 0;
  info.vocabulary_checksum = header.vocabulary_checksum;
  const detail::Section& description = layout.section(kDescription);
  info.vocabulary_description.assign(reinterpret_cast<const char*>(description.data),
                                     description.size);
  return info;
}

}  // namespace binbow
