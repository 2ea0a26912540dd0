// .bbdb: save → load → identical queries; damaged files rejected clearly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "core/crc32c.h"
#include "support/test_support.h"

namespace binbow {
namespace {

struct Fixture {
  Vocabulary vocabulary = test::clustered_vocabulary();
  std::vector<DescriptorMatrix> images;
  Database database{vocabulary, {true, 1}};

  explicit Fixture(std::size_t count = 40) {
    std::mt19937_64 rng(3);
    for (std::size_t i = 0; i < count; ++i) {
      images.push_back(test::clustered_descriptors(10 + i % 30, 32, 40, 0.08, rng));
      const EntryId id = database.add(images.back().view());
      if (i % 4 == 0) database.set_label(id, "image_" + std::to_string(i) + ".png");
    }
    database.remove(static_cast<EntryId>(count / 3));
    database.remove(static_cast<EntryId>(count / 2));
  }
};

void expect_equivalent(const Database& a, const Database& b, const Fixture& fixture) {
  EXPECT_EQ(a.size(), b.size());
  EXPECT_EQ(a.next_entry_id(), b.next_entry_id());
  EXPECT_EQ(a.vocabulary().checksum(), b.vocabulary().checksum());
  EXPECT_EQ(a.options().direct_index, b.options().direct_index);
  EXPECT_EQ(a.options().direct_index_levels_up, b.options().direct_index_levels_up);
  for (EntryId id = 0; id < a.next_entry_id(); ++id) {
    ASSERT_EQ(a.contains(id), b.contains(id));
    if (!a.contains(id)) continue;
    EXPECT_EQ(a.label(id), b.label(id));
    if (a.options().direct_index) {
      EXPECT_EQ(a.feature_vector(id), b.feature_vector(id));
    }
  }
  for (std::size_t i = 0; i < fixture.images.size() && i < 200; ++i) {
    BowVector bow;
    a.vocabulary().transform(fixture.images[i].view(), bow);
    EXPECT_EQ(a.query(bow, 1000), b.query(bow, 1000));
  }
}

TEST(DatabaseFile, SaveLoadRoundTrip) {
  const Fixture fixture;
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  fixture.database.save(path);
  const Database loaded = Database::load(path);
  expect_equivalent(fixture.database, loaded, fixture);
  // The loaded database keeps working: adds continue the id sequence.
  Database reloaded = Database::load(path);
  EXPECT_EQ(reloaded.add(fixture.images[0].view()), fixture.database.next_entry_id());
  EXPECT_EQ(fixture.database.serialize(), loaded.serialize()) << "saving is deterministic";
}

TEST(DatabaseFile, LargeDatabaseRoundTrip) {
  // Thousands of entries: postings in both index tiers when saved.
  const Fixture fixture(5000);
  const auto bytes = fixture.database.serialize();
  const Database loaded = Database::deserialize(bytes.data(), bytes.size(), "memory");
  expect_equivalent(fixture.database, loaded, fixture);
  EXPECT_EQ(loaded.serialize(), bytes);
}

TEST(DatabaseFile, SaveStreamsTheBytesSerializeReturns) {
  // More than the writer's 1 MiB buffer in the posting sections, segments and
  // a tail, removed entries, labels, the vocabulary included or not.
  const Fixture fixture(12000);
  test::TempDir dir;
  for (const bool include_vocabulary : {true, false}) {
    const std::string path = dir.file("db.bbdb");
    fixture.database.save(path, include_vocabulary);
    EXPECT_EQ(test::read_file(path), fixture.database.serialize(include_vocabulary));
  }
}

TEST(DatabaseFile, WithoutDirectIndexOrLabels) {
  const Vocabulary vocabulary = test::clustered_vocabulary();
  Database database(vocabulary, {false, 0});
  Fixture fixture(5);
  for (const auto& image : fixture.images) database.add(image.view());
  const auto bytes = database.serialize();
  const Database loaded = Database::deserialize(bytes.data(), bytes.size(), "memory");
  expect_equivalent(database, loaded, fixture);
  // Empty database.
  Database empty(vocabulary);
  const auto empty_bytes = empty.serialize();
  EXPECT_EQ(Database::deserialize(empty_bytes.data(), empty_bytes.size(), "memory").size(), 0u);
}

TEST(DatabaseFile, VocabularyByChecksum) {
  const Fixture fixture;
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  fixture.database.save(path, false);
  try {
    Database::load(path);
    FAIL() << "a file without vocabulary needs one";
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_NE(e.problem().find("does not include its vocabulary"), std::string::npos) << e.what();
  }
  expect_equivalent(fixture.database, Database::load(path, fixture.vocabulary), fixture);

  try {
    Database::load(path, test::clustered_vocabulary(2));
    FAIL() << "a different vocabulary must be rejected";
  } catch (const FileError& e) {
    EXPECT_NE(e.problem().find("different vocabulary"), std::string::npos) << e.what();
  }
  // Same tree, other scoring: a different vocabulary for the scores.
  EXPECT_THROW(Database::load(path, fixture.vocabulary.with_scoring(Scoring::kL2)), FileError);

  const DatabaseFileInfo info = Database::inspect(path);
  EXPECT_EQ(info.entries, fixture.database.size());
  EXPECT_EQ(info.next_entry_id, fixture.database.next_entry_id());
  EXPECT_FALSE(info.vocabulary_included);
  EXPECT_TRUE(info.direct_index);
  EXPECT_EQ(info.direct_index_levels_up, 1u);
  EXPECT_EQ(info.vocabulary_checksum, fixture.vocabulary.checksum());
  EXPECT_EQ(info.vocabulary_description, fixture.vocabulary.description());
}

TEST(DatabaseFile, DamagedFilesAreRejected) {
  const Fixture fixture(12);
  const std::vector<std::uint8_t> bytes = fixture.database.serialize();
  const auto load = [](const std::vector<std::uint8_t>& data) {
    return Database::deserialize(data.data(), data.size(), "damaged.bbdb");
  };
  ASSERT_NO_THROW(load(bytes));

  // Truncated anywhere, including inside the header and the table.
  for (std::size_t size = 0; size < bytes.size(); size += 1 + size / 7) {
    const std::vector<std::uint8_t> truncated(bytes.begin(), bytes.begin() + size);
    EXPECT_THROW(load(truncated), FileError) << "truncated to " << size;
  }
  // Any single flipped bit.
  for (std::size_t at = 0; at < bytes.size(); at += 1 + at / 50) {
    std::vector<std::uint8_t> flipped = bytes;
    flipped[at] ^= static_cast<std::uint8_t>(1u << (at % 8));
    EXPECT_THROW(load(flipped), FileError) << "bit flipped at byte " << at;
  }
  // Appended garbage.
  std::vector<std::uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_THROW(load(longer), FileError);

  std::vector<std::uint8_t> wrong_magic = bytes;
  wrong_magic[0] = 'X';
  try {
    load(wrong_magic);
    FAIL();
  } catch (const FileError& e) {
    EXPECT_NE(e.problem().find("not a binbow database"), std::string::npos) << e.what();
  }
  // A vocabulary file is not a database.
  const std::vector<std::uint8_t> vocabulary_bytes = fixture.vocabulary.serialize();
  EXPECT_THROW(load(vocabulary_bytes), FileError);
}

// Why a .bbdb image is refused ("loaded" if it is not).
std::string load_problem(const std::vector<std::uint8_t>& data) {
  try {
    Database::deserialize(data.data(), data.size(), "hostile.bbdb");
  } catch (const FileError& e) {
    return e.problem();
  }
  return "loaded";
}

// A section of a .bbdb image changed in place, its CRC and the table's
// recomputed: content that passes every checksum but not the reader's checks.
std::vector<std::uint8_t> with_section(
    const std::vector<std::uint8_t>& bytes, std::uint32_t section,
    const std::function<void(std::uint8_t*, std::size_t)>& change) {
  constexpr std::size_t kTable = 64, kEntry = 24, kSections = 11;
  std::vector<std::uint8_t> changed = bytes;
  std::uint8_t* entry = changed.data() + kTable + section * kEntry;
  std::uint64_t offset = 0, length = 0;
  std::memcpy(&offset, entry + 8, 8);
  std::memcpy(&length, entry + 16, 8);
  change(changed.data() + offset, length);
  const std::uint32_t crc = detail::crc32c(changed.data() + offset, length);
  std::memcpy(entry + 4, &crc, 4);
  const std::uint32_t table_crc = detail::crc32c(changed.data() + kTable, kSections * kEntry);
  std::memcpy(changed.data() + kTable + kSections * kEntry, &table_crc, 4);
  return changed;
}

void expect_refused(const std::vector<std::pair<std::vector<std::uint8_t>, std::string>>& cases) {
  for (const auto& [data, expected] : cases) {
    const std::string found = load_problem(data);
    EXPECT_NE(found.find(expected), std::string::npos)
        << "expected '" << expected << "': " << found;
  }
}

void put_u32(std::uint8_t* at, std::uint32_t value) {
  std::memcpy(at, &value, 4);
}

// Each hostile version-3 index is refused with a message naming the problem.
TEST(DatabaseFile, InconsistentPartsRowsAndDirectIndexAreRefused) {
  const Fixture fixture(12);  // removed: entries 4 and 6
  const std::vector<std::uint8_t> bytes = fixture.database.serialize();
  ASSERT_EQ(load_problem(bytes), "loaded");
  enum : std::uint32_t { kParts = 3, kRows = 4, kPostings = 5, kDivisors = 6, kDirect = 8 };
  const auto posting = [&](const std::function<void(std::uint8_t*)>& change) {
    return with_section(bytes, kPostings, [&](std::uint8_t* d, std::size_t) { change(d); });
  };
  // A database of vectors that transform does not make: rows of weights.
  Database hand_made(fixture.vocabulary, {false, 0});
  hand_made.add(BowVector({{0, 0.25f}, {3, 0.5f}}));
  hand_made.add(BowVector({{0, 0.75f}}));
  const std::vector<std::uint8_t> weights = hand_made.serialize();
  ASSERT_EQ(load_problem(weights), "loaded");
  const auto weight_posting = [&](const std::function<void(std::uint8_t*)>& change) {
    return with_section(weights, kPostings, [&](std::uint8_t* d, std::size_t) { change(d); });
  };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  expect_refused({
      {with_section(bytes, kParts, [&](std::uint8_t* d, std::size_t) { put_u32(d, 0); }),
       "rows for"},
      {with_section(bytes, kParts,
                    [&](std::uint8_t* d, std::size_t) { put_u32(d + 4, 0xFFFFFFF0u); }),
       "the parts count"},
      {with_section(bytes, kRows,
                    [&](std::uint8_t* d, std::size_t) {
                      std::vector<std::uint8_t> first(d, d + 8);
                      std::memmove(d, d + 8, 8);
                      std::memcpy(d + 8, first.data(), 8);
                    }),
       "not in order"},
      {with_section(bytes, kRows, [&](std::uint8_t* d, std::size_t) { put_u32(d, 1u << 30); }),
       "beyond"},
      {with_section(bytes, kRows, [&](std::uint8_t* d, std::size_t) { put_u32(d + 4, 0); }),
       "invalid length"},
      // The first row: its header (gap width 1, counts), then its first
      // posting's 1-byte gap (the entry itself) and count.
      {posting([](std::uint8_t* d) { d[1] = 4; }), "missing entry"},
      {posting([](std::uint8_t* d) { d[1] = 12; }), "missing entry"},
      // Gap widths other than 1 and 2, unknown kinds.
      {posting([](std::uint8_t* d) { d[0] = 0; }), "malformed posting"},
      {posting([](std::uint8_t* d) { d[0] = 3; }), "malformed posting"},
      {posting([](std::uint8_t* d) { d[0] = 0x31; }), "malformed posting"},
      {posting([](std::uint8_t* d) { d[2] = 0; }), "a count of 0"},
      // Weights as counts: the row's length no longer fits its stride.
      {posting([](std::uint8_t* d) { d[0] = 1; }), "malformed posting"},
      // Divisors: not finite, not positive, of a removed entry (4), missing
      // for an entry with counts (0, in the first row).
      {with_section(bytes, kDivisors,
                    [&](std::uint8_t* d, std::size_t) {
                      const double inf = std::numeric_limits<double>::infinity();
                      std::memcpy(d + 8, &inf, 8);
                    }),
       "entry 1 has an invalid divisor"},
      {with_section(bytes, kDivisors,
                    [&](std::uint8_t* d, std::size_t) {
                      const double negative = -2;
                      std::memcpy(d + 8, &negative, 8);
                    }),
       "entry 1 has an invalid divisor"},
      {with_section(bytes, kDivisors,
                    [&](std::uint8_t* d, std::size_t) {
                      const double one = 1;
                      std::memcpy(d + 4 * 8, &one, 8);
                    }),
       "entry 4 has an invalid divisor"},
      {with_section(bytes, kDivisors, [&](std::uint8_t* d, std::size_t) { std::memset(d, 0, 8); }),
       "which has no divisor"},
      // A row whose last posting is cut short: the rows no longer cover the
      // postings section.
      {with_section(bytes, kRows, [&](std::uint8_t* d, std::size_t) { d[4] -= 1; }),
       "trailing data"},
      {weight_posting([&](std::uint8_t* d) { std::memcpy(d + 2, &nan, 4); }), "non-finite"},
      {with_section(bytes, kDirect, [&](std::uint8_t* d, std::size_t) { d[0] = 7; }),
       "unknown layout"},
      {with_section(bytes, kDirect, [&](std::uint8_t* d, std::size_t) { d[1] ^= 1; }),
       "not what its"},
      {with_section(bytes, kDirect, [&](std::uint8_t* d, std::size_t) { d[6] = 0; }),
       "not strictly increasing"},
  });
}

// A database over word ids has no vocabulary to compute weights from
// counts: a divisor is refused (a fuzzing seed: 3 entries over word ids).
TEST(DatabaseFile, DivisorsOverWordIdsAreRefused) {
  const std::vector<std::uint8_t> bytes =
      test::read_file(test::source_path("fuzz/corpus/bbdb/over_word_ids_v3.bbdb"));
  ASSERT_EQ(load_problem(bytes), "loaded");
  enum : std::uint32_t { kDivisors = 6 };
  expect_refused({{with_section(bytes, kDivisors,
                                [&](std::uint8_t* d, std::size_t) {
                                  const double one = 1;
                                  std::memcpy(d, &one, 8);
                                }),
                   "entry 0 has an invalid divisor"}});
}

// The same for a version-2 index (a fuzzing seed: 3 entries over word ids).
TEST(DatabaseFile, InconsistentVersion2IndexIsRefused) {
  const std::vector<std::uint8_t> bytes =
      test::read_file(test::source_path("fuzz/corpus/bbdb/over_word_ids_v2.bbdb"));
  ASSERT_EQ(load_problem(bytes), "loaded");
  const auto u16 = [](std::uint8_t* at, std::uint16_t value) { std::memcpy(at, &value, 2); };
  enum : std::uint32_t { kRows = 4, kEntries = 5, kWeights = 6 };
  expect_refused({
      {with_section(bytes, kRows, [&](std::uint8_t* d, std::size_t) { put_u32(d + 4, 0); }),
       "invalid length"},
      {with_section(bytes, kEntries, [&](std::uint8_t* d, std::size_t) { u16(d, 3); }),
       "missing entry"},
      {with_section(bytes, kWeights,
                    [&](std::uint8_t* d, std::size_t) {
                      const float nan = std::numeric_limits<float>::quiet_NaN();
                      std::memcpy(d, &nan, 4);
                    }),
       "non-finite"},
  });
}

// Sorted random BoW vectors over ids [0, ids).
BowVector random_word_bow(std::size_t words, std::size_t ids, std::mt19937_64& rng) {
  std::vector<BowEntry> entries;
  for (std::size_t i = 0; i < words; ++i)
    entries.push_back({static_cast<WordId>(rng() % ids), 0.01f + static_cast<float>(rng() % 100)});
  std::sort(entries.begin(), entries.end(),
            [](const BowEntry& a, const BowEntry& b) { return a.word < b.word; });
  entries.erase(std::unique(entries.begin(), entries.end(),
                            [](const BowEntry& a, const BowEntry& b) { return a.word == b.word; }),
                entries.end());
  return BowVector(std::move(entries));
}

// Over 150,000 ids the index is saved in parts of 65,536 ids, which the
// segments straddle (tail freezes and merges fall anywhere), with removed
// entries dropped on the way; the loaded database answers alike and keeps
// growing alike.
TEST(DatabaseFile, PartsOf65536IdsRoundTrip) {
  std::mt19937_64 rng(5);
  Database database = Database::over_word_ids(Scoring::kL1, {true, 0});
  for (std::size_t i = 0; i < 150'000; ++i) {
    const BowVector bow = random_word_bow(20, 90'000, rng);
    std::vector<NodeId> words;
    for (const BowEntry& e : bow) words.push_back(e.word);
    database.add(bow, FeatureVector::from_assignment(words.data(), words.size()));
    if (i % 7 == 3) database.remove(static_cast<EntryId>(i / 2));
  }
  const std::vector<std::uint8_t> bytes = database.serialize();
  Database loaded = Database::deserialize(bytes.data(), bytes.size(), "parts.bbdb");
  EXPECT_EQ(loaded.size(), database.size());
  EXPECT_EQ(loaded.serialize(), bytes);
  for (EntryId id = 0; id < database.next_entry_id(); id += 97) {
    ASSERT_EQ(loaded.contains(id), database.contains(id));
    if (database.contains(id)) {
      EXPECT_EQ(loaded.feature_vector(id), database.feature_vector(id));
    }
  }
  for (int i = 0; i < 30; ++i) {
    const BowVector bow = random_word_bow(300, 90'000, rng);
    EXPECT_EQ(loaded.query(bow, 50), database.query(bow, 50));
    EXPECT_EQ(loaded.query(bow, 50, 70'000 + i), database.query(bow, 50, 70'000 + i));
    EXPECT_EQ(loaded.add(bow), database.add(bow));
  }
  EXPECT_EQ(loaded.serialize(), database.serialize());
}

// Databases saved in format versions 1 and 2 (the fuzzing seeds) still
// load, answer as the same database saved again in the current version, and
// both versions of a seed hold the same database.
TEST(DatabaseFile, OlderVersionsStillLoad) {
  std::size_t loaded_files = 0;
  // (fuzz/corpus/bbdb/over_word_ids.bbdb names ids too sparse for its size:
  // refused in every version.)
  for (const std::string name :
       {"code8_k3L1", "direct_three", "empty", "plain_two", "removed_one"}) {
    std::vector<std::uint8_t> saved_again[2];
    for (std::uint32_t version : {1u, 2u}) {
      SCOPED_TRACE(name + " version " + std::to_string(version));
      const std::string path =
          test::source_path("fuzz/corpus/bbdb/" + name + (version == 1 ? "" : "_v2") + ".bbdb");
      ASSERT_EQ(Database::inspect(path).version, version);
      const Database old = Database::load(path);
      const std::vector<std::uint8_t> bytes = old.serialize();
      saved_again[version - 1] = bytes;
      const Database current = Database::deserialize(bytes.data(), bytes.size(), "current");
      ASSERT_EQ(current.next_entry_id(), old.next_entry_id());
      ASSERT_EQ(current.size(), old.size());
      for (EntryId id = 0; id < old.next_entry_id(); ++id) {
        ASSERT_EQ(current.contains(id), old.contains(id));
        if (!old.contains(id)) continue;
        EXPECT_EQ(current.label(id), old.label(id));
        if (old.options().direct_index) {
          EXPECT_EQ(current.feature_vector(id), old.feature_vector(id));
        }
      }
      std::mt19937_64 rng(1);
      const std::size_t words = old.vocabulary().empty() ? 70'000 : old.vocabulary().word_count();
      for (int i = 0; i < 20; ++i) {
        const BowVector bow = random_word_bow(8, words, rng);
        EXPECT_EQ(current.query(bow, 10), old.query(bow, 10));
      }
      ++loaded_files;
    }
    EXPECT_EQ(saved_again[0], saved_again[1]) << name;
  }
  EXPECT_EQ(loaded_files, 10u);
}

// A database over word ids (an online vocabulary's) saves its scoring and
// the word-id capacity its index grew to, and continues after load exactly as
// the saved one does.
TEST(DatabaseFile, OverWordIdsRoundTrip) {
  std::mt19937_64 rng(9);
  Database database = Database::over_word_ids(Scoring::kKL, {true, 0});
  std::vector<BowVector> later;
  for (std::size_t i = 0; i < 400; ++i) {
    // Ids up to 150,000: the capacity doubles past 2^16 to 150,000, then 300,000.
    const BowVector bow = random_word_bow(60, 1000 + i * 400, rng);
    std::vector<NodeId> words;
    for (const BowEntry& e : bow) words.push_back(e.word);
    database.add(bow, FeatureVector::from_assignment(words.data(), words.size()));
    if (i % 50 == 7) database.remove(static_cast<EntryId>(i - 3));
  }
  for (int i = 0; i < 20; ++i) later.push_back(random_word_bow(60, 300'000, rng));
  const std::vector<std::uint8_t> bytes = database.serialize();
  Database loaded = Database::deserialize(bytes.data(), bytes.size(), "words.bbdb");
  EXPECT_TRUE(loaded.vocabulary().empty());
  EXPECT_EQ(loaded.scoring(), Scoring::kKL);
  EXPECT_EQ(loaded.serialize(), bytes) << "the capacity and the index round-trip";
  for (EntryId id = 0; id < database.next_entry_id(); ++id) {
    ASSERT_EQ(loaded.contains(id), database.contains(id));
    if (database.contains(id)) {
      EXPECT_EQ(loaded.feature_vector(id), database.feature_vector(id));
    }
  }
  for (const BowVector& bow : later) {
    EXPECT_EQ(loaded.query(bow, 30), database.query(bow, 30));
    EXPECT_EQ(loaded.add(bow), database.add(bow));
  }
  EXPECT_EQ(loaded.serialize(), database.serialize()) << "both grew the same way";

  test::TempDir dir;
  const std::string path = dir.file("words.bbdb");
  database.save(path);
  EXPECT_EQ(Database::load(path).serialize(), database.serialize());
  try {
    Database::load(path, test::clustered_vocabulary());
    FAIL() << "a database over word ids has no vocabulary to check";
  } catch (const FileError& e) {
    EXPECT_NE(e.problem().find("over word ids"), std::string::npos) << e.what();
  }
  EXPECT_EQ(Database::inspect(path).entries, database.size());
}

// Header fields of a database over word ids, rewritten with a valid header
// CRC: a capacity its words do not justify is refused before the index is
// laid out for it.
TEST(DatabaseFile, OverWordIdsCapacityIsBounded) {
  std::mt19937_64 rng(2);
  Database database = Database::over_word_ids(Scoring::kL1, {false, 0});
  database.add(random_word_bow(30, 5000, rng));
  const std::vector<std::uint8_t> bytes = database.serialize();
  const auto with_header_field = [&](std::size_t at, std::uint64_t value, std::size_t width) {
    std::vector<std::uint8_t> changed = bytes;
    for (std::size_t i = 0; i < width; ++i)
      changed[at + i] = static_cast<std::uint8_t>(value >> (8 * i));
    const std::uint32_t crc = detail::crc32c(changed.data(), 60);
    for (std::size_t i = 0; i < 4; ++i) changed[60 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
    return changed;
  };
  EXPECT_EQ(load_problem(with_header_field(52, 65536, 8)), "loaded");
  EXPECT_NE(load_problem(with_header_field(52, std::uint64_t{1} << 32, 8)).find("capacity"),
            std::string::npos);
  EXPECT_NE(load_problem(with_header_field(52, 100, 8)).find("capacity"), std::string::npos);
  EXPECT_NE(load_problem(with_header_field(36, 9, 4)).find("inconsistent header"),
            std::string::npos);
  EXPECT_NE(load_problem(with_header_field(32, 1234, 4)).find("inconsistent header"),
            std::string::npos);
}

TEST(DatabaseFile, InspectVerifiesTheWholeFileByDefault) {
  const Fixture fixture(12);
  test::TempDir dir;
  for (const bool include_vocabulary : {true, false}) {
    SCOPED_TRACE(include_vocabulary ? "with its vocabulary" : "without its vocabulary");
    const std::string path = dir.file("db.bbdb");
    fixture.database.save(path, include_vocabulary);
    EXPECT_EQ(Database::inspect(path).entries, fixture.database.size());
    std::vector<std::uint8_t> bytes = test::read_file(path);
    bytes[bytes.size() - 1] ^= 0x10;  // in the last section (labels)
    test::write_file(path, bytes);
    EXPECT_THROW(Database::inspect(path), FileError);
    EXPECT_EQ(Database::inspect(path, false).entries, fixture.database.size());
  }
}

TEST(DatabaseFile, ErrorsNameTheFile) {
  test::TempDir dir;
  const std::string missing = dir.file("missing.bbdb");
  try {
    Database::load(missing);
    FAIL();
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), missing);
  }
  const std::string garbage = dir.file("garbage.bbdb");
  test::write_file(garbage, std::vector<std::uint8_t>(100, 7));
  EXPECT_THROW(Database::load(garbage), FileError);
  EXPECT_THROW(Database::inspect(garbage), FileError);
}

TEST(DatabaseFile, SaveIsAtomic) {
  const Fixture fixture(5);
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  fixture.database.save(path);
  // Saving below a file fails cleanly and leaves nothing behind.
  EXPECT_THROW(fixture.database.save(dir.file("db.bbdb/inside.bbdb")), FileError);
  EXPECT_EQ(Database::load(path).size(), fixture.database.size());
  // Missing folders are made.
  fixture.database.save(dir.file("no/such/dir/db.bbdb"));
  EXPECT_EQ(Database::load(dir.file("no/such/dir/db.bbdb")).size(), fixture.database.size());
  fixture.database.save(path);  // overwrite
  EXPECT_EQ(Database::load(path).size(), fixture.database.size());
}

}  // namespace
}  // namespace binbow
