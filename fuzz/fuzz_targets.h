// The work of each libFuzzer target, shared with the regression test that
// replays fuzz/corpus/<target>/* through the normal build
// (tests/formats/fuzz_corpus_test.cpp), vocabularies and databases alike. Each function returns for
// a valid file, throws binbow::FileError for an invalid one, and throws std::logic_error when an
// accepted file breaks an invariant (a bug).
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/online_vocabulary.h"
#include "binbow/vocabulary.h"
#include "core/crc32c.h"
#include "core/little_endian.h"
#include "database/background_check.h"
#include "database/database_journal.h"
#include "formats/codecs.h"
#include "formats/container.h"
#include "formats/gzip.h"

namespace binbow::fuzz {

// Every descriptor reaches a word; writing the vocabulary back in `format`
// and reading it again gives the same vocabulary.
inline void check_accepted(const Vocabulary& vocabulary, VocabularyFormat format,
                           detail::DescriptorText text = detail::DescriptorText::kBytes) {
  const std::vector<std::uint8_t> probe(vocabulary.code_size(), 0xA5);
  if (vocabulary.quantize(probe.data()) >= vocabulary.word_count())
    throw std::logic_error("quantize returned a word outside the vocabulary");
  if (format == VocabularyFormat::kBinbow) return;
  const VocabularyTree tree = vocabulary.to_tree();
  std::vector<std::uint8_t> bytes;
  switch (format) {
    case VocabularyFormat::kOrbSlamText:
      bytes = detail::format_orbslam_text(tree);
      break;
    case VocabularyFormat::kOrbSlamBinary:
      bytes = detail::format_orbslam_binary(tree);
      break;
    case VocabularyFormat::kDbow2Yaml:
      bytes = detail::format_dbow2_yaml(tree, text);
      break;
    case VocabularyFormat::kDbow3:
      bytes = detail::format_dbow3_binary(tree);
      break;
    case VocabularyFormat::kFbow:
      bytes = detail::format_fbow(tree);
      break;
    case VocabularyFormat::kVinsBinary:
      bytes = detail::format_vins_binary(tree);
      break;
    default:
      return;
  }
  const Vocabulary again = detail::vocabulary_from_parsed(
      detail::parse_vocabulary_bytes(format, bytes.data(), bytes.size(), "rewritten"), "rewritten");
  if (again.checksum() != vocabulary.checksum())
    throw std::logic_error("writing and reading back changed the vocabulary");
}

inline void load_tree_format(VocabularyFormat format, const std::uint8_t* data, std::size_t size) {
  const detail::ParsedVocabulary parsed =
      detail::parse_vocabulary_bytes(format, data, size, "fuzz");
  check_accepted(detail::vocabulary_from_parsed(parsed, "fuzz"), format, parsed.descriptor_text);
}

// DBoW2 YAML, also through gzip and tar.gz (the container code is fuzzed here).
inline void load_dbow2_yaml(const std::uint8_t* data, std::size_t size) {
  std::size_t contained_size = 0;
  detail::contained_head(data, size, contained_size);
  const detail::ContainedFile file = detail::open_contained(data, size, "fuzz");
  load_tree_format(VocabularyFormat::kDbow2Yaml, file.data, file.size);
}

inline void load_bbw(const std::uint8_t* data, std::size_t size) {
  // Without checksums only the structural checks stand between the bytes and
  // the tree walk: exercise both.
  LoadOptions options;
  options.verify_checksums = size > 0 && (data[size - 1] & 1);
  check_accepted(Vocabulary::deserialize(data, size, "fuzz", options), VocabularyFormat::kBinbow);
}

// Rewrites the header, table and section CRCs of a .bbdb image in place,
// where the layout allows it.
inline void fix_bbdb_checksums(std::vector<std::uint8_t>& bytes) {
  constexpr std::size_t kHeaderSize = 64;
  constexpr std::size_t kSectionEntrySize = 24;
  using detail::crc32c;
  using detail::load_le;
  using detail::store_le;
  if (bytes.size() < kHeaderSize) return;
  std::uint8_t* data = bytes.data();
  const auto sections = load_le<std::uint32_t>(data + 48);
  if (sections > 64) return;
  const std::size_t table_size = sections * kSectionEntrySize;
  if (bytes.size() >= kHeaderSize + table_size + 4) {
    std::uint8_t* table = data + kHeaderSize;
    for (std::uint32_t i = 0; i < sections; ++i) {
      std::uint8_t* e = table + i * kSectionEntrySize;
      const auto offset = load_le<std::uint64_t>(e + 8);
      const auto length = load_le<std::uint64_t>(e + 16);
      if (offset <= bytes.size() && length <= bytes.size() - offset)
        store_le<std::uint32_t>(e + 4, crc32c(data + offset, length));
    }
    store_le<std::uint32_t>(table + table_size, crc32c(table, table_size));
  }
  store_le<std::uint32_t>(data + 60, crc32c(data, 60));
}

// fix_bbdb_checksums for a sectioned file whose sections `nested` are
// sectioned files too (a .bbld's database and online vocabulary): theirs first.
inline void fix_nested_checksums(std::vector<std::uint8_t>& bytes,
                                 const std::vector<std::uint32_t>& nested) {
  constexpr std::size_t kHeaderSize = 64;
  if (bytes.size() < kHeaderSize) return;
  const auto sections = detail::load_le<std::uint32_t>(bytes.data() + 48);
  for (const std::uint32_t section : nested) {
    if (section >= sections || bytes.size() < kHeaderSize + (section + 1) * 24) continue;
    const std::uint8_t* entry = bytes.data() + kHeaderSize + section * 24;
    const auto offset = detail::load_le<std::uint64_t>(entry + 8);
    const auto length = detail::load_le<std::uint64_t>(entry + 16);
    if (offset > bytes.size() || length > bytes.size() - offset) continue;
    std::vector<std::uint8_t> inner(bytes.begin() + static_cast<std::ptrdiff_t>(offset),
                                    bytes.begin() + static_cast<std::ptrdiff_t>(offset + length));
    fix_bbdb_checksums(inner);
    std::copy(inner.begin(), inner.end(), bytes.begin() + static_cast<std::ptrdiff_t>(offset));
  }
  fix_bbdb_checksums(bytes);
}

// An accepted database answers queries, returns its direct index and
// survives a save/load round trip unchanged.
inline void check_accepted_database(const Database& database) {
  const std::size_t words = std::min<std::size_t>(database.vocabulary().word_count(), 16);
  std::vector<BowEntry> entries;
  for (WordId w = 0; w < words; ++w) entries.push_back({w, 1.0f / static_cast<float>(words)});
  const auto results = database.query(BowVector(entries), 5);
  for (const auto& result : results)
    if (!database.contains(result.entry)) throw std::logic_error("query returned a missing entry");
  std::size_t live = 0;
  for (EntryId id = 0; id < database.next_entry_id(); ++id) {
    if (!database.contains(id)) continue;
    ++live;
    if (database.options().direct_index) (void)database.feature_vector(id);
    (void)database.label(id);
  }
  if (live != database.size()) throw std::logic_error("size() disagrees with contains()");
  const std::vector<std::uint8_t> saved = database.serialize();
  const Database again = Database::deserialize(saved.data(), saved.size(), "resaved");
  if (again.serialize() != saved) throw std::logic_error("save/load round trip changed the file");
}

// The .bbdb image loaded as Database::load does: from a file, mapped, the
// check of its large sections held while the database answers queries and
// returns feature vectors over bytes not verified yet (which must never
// crash). Whether it is accepted in the end.
inline bool load_mapped_bbdb(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/binbow-fuzz-" + std::to_string(::getpid()) + ".bbdb";
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw std::runtime_error("cannot write " + path);
  const bool written = std::fwrite(data, 1, size, file) == size;
  if (std::fclose(file) != 0 || !written) throw std::runtime_error("cannot write " + path);
  struct Remove {  // at once: the mapping keeps the file's bytes
    ~Remove() { std::remove(path.c_str()); }
  } remove;
  struct Hold {
    Hold() { detail::hold_background_checks() = true; }
    ~Hold() { detail::hold_background_checks() = false; }
  } hold;
  try {
    const Database database = Database::load(path);
    const std::size_t words = std::min<std::size_t>(database.vocabulary().word_count(), 16);
    std::vector<BowEntry> entries;
    for (WordId w = 0; w < words; ++w) entries.push_back({w, 1.0f / static_cast<float>(words)});
    (void)database.query(BowVector(entries), 5);
    for (EntryId id = 0; id < database.next_entry_id() && database.options().direct_index; ++id) {
      if (!database.contains(id)) continue;
      try {
        (void)database.feature_vector(id);
      } catch (const FileError&) {
      }
    }
    detail::hold_background_checks() = false;
    database.wait_until_verified();
    return true;
  } catch (const FileError&) {
    return false;
  }
}

// .bbdb: the input as is (the CRCs reject almost all mutations), then with
// its CRCs recomputed, so that mutations reach the structural checks behind
// them; both also loaded from a file, mapped, which must accept exactly what
// deserialize() accepts. Throws FileError if the input as is was rejected.
inline void load_bbdb(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> fixed(data, data + size);
  fix_bbdb_checksums(fixed);
  bool accepted = true;
  try {
    check_accepted_database(Database::deserialize(fixed.data(), fixed.size(), "fuzz"));
  } catch (const FileError&) {
    accepted = false;
  }
  if (load_mapped_bbdb(fixed.data(), fixed.size()) != accepted)
    throw std::logic_error("load() and deserialize() disagree on a file");
  accepted = load_mapped_bbdb(data, size);
  check_accepted_database(Database::deserialize(data, size, "fuzz"));
  if (!accepted) throw std::logic_error("load() refuses a file deserialize() accepts");
}

// Rewrites the header CRC of a database journal and every record's CRCs,
// as far as the records' lengths lead; with `base`, the header names it.
inline void fix_journal_checksums(std::vector<std::uint8_t>& bytes,
                                  const detail::BaseId* base = nullptr) {
  if (bytes.size() < detail::kJournalHeaderSize) return;
  if (base != nullptr) {
    detail::store_le<std::uint64_t>(bytes.data() + 16, base->size);
    detail::store_le<std::uint32_t>(bytes.data() + 24, base->checksum);
  }
  detail::store_le<std::uint32_t>(bytes.data() + 28, detail::crc32c(bytes.data(), 28));
  const detail::BaseId extended{detail::load_le<std::uint64_t>(bytes.data() + 16),
                                detail::load_le<std::uint32_t>(bytes.data() + 24)};
  std::size_t at = detail::kJournalHeaderSize;
  while (bytes.size() - at >= detail::kJournalRecordHeaderSize) {
    std::uint8_t* head = bytes.data() + at;
    const auto length = detail::load_le<std::uint64_t>(head);
    const std::size_t body = at + detail::kJournalRecordHeaderSize;
    if (length > bytes.size() - body) {  // a torn append: its header stays valid
      detail::store_le<std::uint32_t>(head + 12, detail::record_header_crc(head, extended));
      return;
    }
    detail::store_le<std::uint32_t>(
        head + 8, detail::crc32c(bytes.data() + body, static_cast<std::size_t>(length)));
    detail::store_le<std::uint32_t>(head + 12, detail::record_header_crc(head, extended));
    at = body + static_cast<std::size_t>(length);
  }
}

// The base every fuzzed journal extends: a small database over word ids,
// with a direct index, labels and a removed entry.
inline const std::vector<std::uint8_t>& journal_fuzz_base() {
  static const std::vector<std::uint8_t> bytes = [] {
    Database database = Database::over_word_ids(Scoring::kL1, {true, 0});
    for (WordId i = 0; i < 6; ++i) {
      const std::vector<BowEntry> entries{{i, 0.25f}, {i + 3, 0.5f}, {7 * i + 10, 0.25f}};
      std::vector<NodeId> nodes;
      for (const BowEntry& e : entries) nodes.push_back(e.word);
      database.add(BowVector(entries), FeatureVector::from_assignment(nodes.data(), nodes.size()),
                   i % 2 == 0 ? "image_" + std::to_string(i) : "");
    }
    database.remove(2);
    return database.serialize();
  }();
  return bytes;
}

// A database journal replayed over journal_fuzz_base(): the input as is
// (which must name that base), then with the base named and every CRC
// recomputed, so that mutations reach the decoding of the changes. The
// result is an accepted database.
inline void load_bbdb_journal(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t>& base = journal_fuzz_base();
  detail::BaseId id;
  if (!detail::base_id_of(base.data(), base.size(), id))
    throw std::logic_error("the fuzz base is no sectioned file");
  const auto replay = [&](const std::uint8_t* journal, std::size_t journal_size) {
    Database database = Database::deserialize(base.data(), base.size(), "base");
    const detail::JournalScan scan = detail::scan_journal(journal, journal_size, "fuzz");
    if (scan.valid_end + scan.torn_bytes != journal_size)
      throw std::logic_error("the scan lost bytes of the journal");
    detail::replay_journal(database, scan, id, "fuzz", base.size() + journal_size);
    check_accepted_database(database);
  };
  std::vector<std::uint8_t> fixed(data, data + size);
  fix_journal_checksums(fixed, &id);
  try {
    replay(fixed.data(), fixed.size());
  } catch (const FileError&) {
  }
  replay(data, size);
}

// An accepted online vocabulary survives a save/load round trip unchanged,
// and keeps working: it transforms and adds an image.
inline void check_accepted_online(OnlineVocabulary vocabulary) {
  const std::vector<std::uint8_t> saved = vocabulary.serialize();
  if (OnlineVocabulary::deserialize(saved.data(), saved.size(), "resaved").serialize() != saved)
    throw std::logic_error("save/load round trip changed the online vocabulary");
  const std::size_t code_size = vocabulary.code_size();
  DescriptorMatrix probe(code_size);
  for (const WordId word : vocabulary.words()) probe.append(vocabulary.word_descriptor(word));
  probe.append(std::vector<std::uint8_t>(code_size, 0xA5).data());
  BowVector bow;
  FeatureVector features;
  vocabulary.transform(probe, bow, &features);
  const bool full = vocabulary.image_count() == 0xFFFFFFFFu ||
                    probe.rows() > OnlineVocabulary::kNoWord - vocabulary.next_word_id();
  if (full) {  // a state at the counters' limits: add_image must refuse, not wrap
    try {
      vocabulary.add_image(probe);
    } catch (const InvalidArgument&) {
      return;
    }
    throw std::logic_error("add_image accepted an image beyond the counters' limits");
  }
  const OnlineImageWords added = vocabulary.add_image(probe);
  for (const WordId word : added.words)
    if (!vocabulary.contains(word)) throw std::logic_error("add_image returned a missing word");
}

// .bbov: as is, then with its CRCs recomputed (its header and section table
// are laid out as .bbdb's), so that mutations reach the checks behind them.
inline void load_bbov(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> fixed(data, data + size);
  fix_bbdb_checksums(fixed);
  try {
    check_accepted_online(OnlineVocabulary::deserialize(fixed.data(), fixed.size(), "fuzz"));
  } catch (const FileError&) {
  }
  check_accepted_online(OnlineVocabulary::deserialize(data, size, "fuzz"));
}

// gzip: the head the format sniffers read is a prefix of the whole, and
// what gunzip accepts survives gzip and gunzip unchanged.
inline void load_gzip(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> head = detail::gunzip_head(data, size, 1024);
  const std::vector<std::uint8_t> whole =
      detail::gunzip(data, size, "fuzz", detail::gunzip_limit(size));
  if (head.size() > whole.size() || !std::equal(head.begin(), head.end(), whole.begin()))
    throw std::logic_error("gunzip_head is not a prefix of gunzip");
  const std::vector<std::uint8_t> again = detail::gzip(whole);
  if (detail::gunzip(again.data(), again.size(), "regzipped", detail::gunzip_limit(again.size())) !=
      whole)
    throw std::logic_error("gzip and gunzip changed the data");
}

// tar: the member found lies inside the archive, a prefix of the archive
// (what the sniffers read) finds the same member, and so does the whole
// archive gzipped (as .tar.gz vocabularies are read).
inline void load_tar(const std::uint8_t* data, std::size_t size) {
  std::size_t offset = 0, member = 0;
  if (!detail::find_tar_member(data, size, "fuzz", false, offset, member))
    throw FileError("fuzz", "not a tar archive");
  if (offset > size || member > size - offset)
    throw std::logic_error("the tar member extends beyond the archive");
  std::size_t head_offset = 0, head_member = 0;
  try {
    if (detail::find_tar_member(data, std::min<std::size_t>(size, offset + 1), "fuzz", true,
                                head_offset, head_member) &&
        (head_offset != offset || head_member != member))
      throw std::logic_error("a prefix of the archive gives another member");
  } catch (const FileError&) {
  }
  if (member == 0) return;  // open_contained rejects an empty file
  const std::vector<std::uint8_t> gzipped =
      detail::gzip(std::vector<std::uint8_t>(data, data + size));
  const detail::ContainedFile file = detail::open_contained(gzipped.data(), gzipped.size(), "fuzz");
  if (!file.tar || file.size != member || std::memcmp(file.data, data + offset, member) != 0)
    throw std::logic_error("the gzipped archive gives another member");
}

// Target names (fuzz_<name>, fuzz/corpus/<name>/) and their functions.
struct Target {
  const char* name;
  void (*run)(const std::uint8_t*, std::size_t);
};
inline const Target kTargets[] = {
    {"orbslam_text", [](const std::uint8_t* d,
                        std::size_t n) { load_tree_format(VocabularyFormat::kOrbSlamText, d, n); }},
    {"orbslam_binary",
     [](const std::uint8_t* d, std::size_t n) {
       load_tree_format(VocabularyFormat::kOrbSlamBinary, d, n);
     }},
    {"dbow2_yaml", load_dbow2_yaml},
    {"dbow3", [](const std::uint8_t* d,
                 std::size_t n) { load_tree_format(VocabularyFormat::kDbow3, d, n); }},
    {"fbow",
     [](const std::uint8_t* d, std::size_t n) { load_tree_format(VocabularyFormat::kFbow, d, n); }},
    {"vins_binary", [](const std::uint8_t* d,
                       std::size_t n) { load_tree_format(VocabularyFormat::kVinsBinary, d, n); }},
    {"bbw", load_bbw},
    {"bbdb", load_bbdb},
    {"bbdb_journal", load_bbdb_journal},
    {"bbov", load_bbov},
    {"gzip", load_gzip},
    {"tar", load_tar},
};

// The body of LLVMFuzzerTestOneInput for target `name` of `targets`.
template <std::size_t N>
int run_target(const Target (&targets)[N], const char* name, const std::uint8_t* data,
               std::size_t size) {
  for (const Target& target : targets) {
    if (std::string(target.name) != name) continue;
    try {
      target.run(data, size);
    } catch (const FileError&) {
    }
    return 0;
  }
  throw std::logic_error(std::string("unknown fuzz target ") + name);
}

inline int run_target(const char* name, const std::uint8_t* data, std::size_t size) {
  return run_target(kTargets, name, data, size);
}

}  // namespace binbow::fuzz
