// Database::load maps a .bbdb file: a loaded database answers as the saved
// one, before and after the background check of its file; a damaged file
// never crashes a call, and once the check finds the damage every call
// throws FileError. Where the file cannot be mapped it is read into memory,
// with the same answers and checks.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "core/file_io.h"
#include "database/background_check.h"
#include "support/query_results.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::bbdb_section;

constexpr std::uint32_t kPostingsSection = 5;
constexpr std::uint32_t kDirectDataSection = 8;

struct Fixture {
  Vocabulary vocabulary = test::clustered_vocabulary();
  std::vector<BowVector> queries;
  Database database{vocabulary, {true, 1}};

  explicit Fixture(std::size_t count = 3000) {
    std::mt19937_64 rng(5);
    for (std::size_t i = 0; i < count; ++i) {
      const DescriptorMatrix image = test::clustered_descriptors(10 + i % 30, 32, 40, 0.08, rng);
      database.add(image.view(), i % 5 == 0 ? "image_" + std::to_string(i) : std::string());
      if (i % 50 == 0) {
        BowVector bow;
        vocabulary.transform(image.view(), bow);
        queries.push_back(bow);
      }
    }
    for (EntryId id = 7; id < count; id += 97) database.remove(id);
  }
};

// Holds the checks of databases loaded in the background while it lives.
class HeldChecks {
 public:
  HeldChecks() { detail::hold_background_checks() = true; }
  ~HeldChecks() { release(); }
  void release() { detail::hold_background_checks() = false; }
};

// Maps no file while it lives: MappedFile reads every file into memory, as
// on a file system that cannot map.
class RefusedMappings {
 public:
  RefusedMappings() { detail::refuse_mappings() = true; }
  ~RefusedMappings() { detail::refuse_mappings() = false; }
};

void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr);
  ASSERT_EQ(std::fwrite(bytes.data(), 1, bytes.size(), file), bytes.size());
  std::fclose(file);
}

void expect_same_answers(const Database& expected, const Database& loaded, const Fixture& fixture) {
  for (const BowVector& query : fixture.queries)
    for (QueryMode mode : {QueryMode::kExact, QueryMode::kFast})
      ASSERT_EQ(expected.query(query, 20, {mode, 1}), loaded.query(query, 20, {mode, 1}));
  for (EntryId id = 0; id < expected.next_entry_id(); id += 13) {
    ASSERT_EQ(expected.contains(id), loaded.contains(id));
    if (!expected.contains(id)) continue;
    EXPECT_EQ(expected.feature_vector(id), loaded.feature_vector(id));
    EXPECT_EQ(expected.label(id), loaded.label(id));
  }
}

TEST(DatabaseMapped, AnswersAsSavedBeforeAndAfterTheCheck) {
  const Fixture fixture;
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  fixture.database.save(path);
  {
    // Before the check: L1 sums DBoW2's terms, not minimums; the same bits.
    HeldChecks held;
    const Database loaded = Database::load(path, fixture.vocabulary);
    for (const BowVector& query : fixture.queries)
      ASSERT_EQ(fixture.database.query(query, 20, {QueryMode::kExact, 1}),
                loaded.query(query, 20, {QueryMode::kExact, 1}));
    held.release();
    loaded.wait_until_verified();
    expect_same_answers(fixture.database, loaded, fixture);
    EXPECT_EQ(loaded.serialize(), fixture.database.serialize());
  }
  const Database verified = Database::load(path, fixture.vocabulary, {Verification::kBeforeReturn});
  expect_same_answers(fixture.database, verified, fixture);
  EXPECT_EQ(verified.serialize(), fixture.database.serialize());
}

TEST(DatabaseMapped, ReadIntoMemoryWhereTheFileCannotBeMapped) {
  Fixture fixture;
  test::TempDir dir;
  const std::string mapped_path = dir.file("mapped.bbdb"), read_path = dir.file("read.bbdb");
  fixture.database.save(mapped_path);
  fixture.database.save(read_path);
  Database mapped = Database::load(mapped_path, fixture.vocabulary);
  mapped.wait_until_verified();
  RefusedMappings refused;
  ASSERT_FALSE(detail::MappedFile(read_path).mapped());
  const std::vector<std::uint8_t> saved = test::read_file(read_path);
  const auto [offset, length] = bbdb_section(saved, kPostingsSection);
  std::optional<Database> read;
  {
    HeldChecks held;
    read.emplace(Database::load(read_path, fixture.vocabulary));
    for (const BowVector& query : fixture.queries)
      ASSERT_EQ(mapped.query(query, 20, {QueryMode::kExact, 1}),
                read->query(query, 20, {QueryMode::kExact, 1}));
    // Rewritten in place (undefined under a mapping), the file no longer
    // matters: the index and its check read the copy.
    std::FILE* file = std::fopen(read_path.c_str(), "r+b");
    ASSERT_NE(file, nullptr);
    const std::vector<std::uint8_t> zeros(length, 0);
    ASSERT_EQ(std::fseek(file, static_cast<long>(offset), SEEK_SET), 0);
    ASSERT_EQ(std::fwrite(zeros.data(), 1, zeros.size(), file), zeros.size());
    ASSERT_EQ(std::fclose(file), 0);
  }
  read->wait_until_verified();
  expect_same_answers(fixture.database, *read, fixture);
  expect_same_answers(mapped, *read, fixture);
  EXPECT_EQ(read->serialize(), fixture.database.serialize());
  // Removals compact the segment read into memory as they do a mapped one.
  for (EntryId id = 1; id < fixture.database.next_entry_id(); id += 2) {
    if (!fixture.database.contains(id)) continue;
    fixture.database.remove(id);
    mapped.remove(id);
    read->remove(id);
  }
  expect_same_answers(mapped, *read, fixture);
  EXPECT_EQ(read->serialize(false), mapped.serialize(false));
  // A damaged file read into memory: found by the background check, or
  // before load returns.
  std::vector<std::uint8_t> damaged = saved;
  damaged[offset + length / 2] ^= 0x10;
  write_bytes(read_path, damaged);
  for (Verification verification : {Verification::kBackground, Verification::kBeforeReturn}) {
    try {
      const Database loaded = Database::load(read_path, fixture.vocabulary, {verification});
      EXPECT_EQ(verification, Verification::kBackground) << "kBeforeReturn loaded a damaged file";
      loaded.wait_until_verified();
      FAIL() << "damage not found";
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), read_path);
      EXPECT_NE(e.problem().find("'postings'"), std::string::npos) << e.what();
    }
  }
}

TEST(DatabaseMapped, DamagedPostingsNeverCrashAndThenEveryCallThrows) {
  const Fixture fixture;
  // 65,536 entries of word 0 alone: a query of word 1 finds none of them,
  // unless a sum left over from another query is read as theirs.
  Database other = Database::over_word_ids(Scoring::kL1, DatabaseOptions{false, 0});
  for (int i = 0; i < 65'536; ++i) other.add(BowVector(std::vector<BowEntry>{{0, 1.0f}}));
  const BowVector word_one(std::vector<BowEntry>{{1, 1.0f}});
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  const std::vector<std::uint8_t> saved = fixture.database.serialize();
  const auto [offset, length] = bbdb_section(saved, kPostingsSection);
  ASSERT_GT(length, 1000u);
  std::mt19937_64 rng(9);
  // Garbage everywhere (wrong widths, gaps far past the part, NaN weights),
  // then every byte 0xFF, then one byte.
  for (int damage = 0; damage < 3; ++damage) {
    std::vector<std::uint8_t> bytes = saved;
    for (std::size_t i = 0; i < length; ++i) {
      std::uint8_t& byte = bytes[offset + i];
      if (damage == 0) byte = static_cast<std::uint8_t>(rng());
      if (damage == 1) byte = 0xFF;
    }
    if (damage == 2) bytes[offset + length / 2] ^= 0x10;
    write_bytes(path, bytes);
    HeldChecks held;
    Database loaded = Database::load(path, fixture.vocabulary);
    for (const BowVector& query : fixture.queries) {
      loaded.query(query, 20, {QueryMode::kExact, 1});
      loaded.query(query, 20, {QueryMode::kExact, 2});
    }
    EXPECT_EQ(loaded.size(), fixture.database.size());
    // What the damaged postings summed leaves nothing behind for the
    // thread's next queries, of another database.
    EXPECT_TRUE(other.query(word_one, 10).empty()) << "damage " << damage;
    held.release();
    try {
      loaded.wait_until_verified();
      FAIL() << "damage " << damage << " not found";
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), path);
      EXPECT_NE(e.problem().find("'postings'"), std::string::npos) << e.what();
      EXPECT_NE(e.problem().find("backup"), std::string::npos) << e.what();
    }
    EXPECT_THROW(loaded.query(fixture.queries[0], 20), FileError);
    EXPECT_THROW(loaded.size(), FileError);
    EXPECT_THROW(loaded.contains(0), FileError);
    EXPECT_THROW(loaded.add(fixture.queries[0]), FileError);
    EXPECT_THROW(loaded.remove(0), FileError);
    EXPECT_THROW(loaded.save(dir.file("copy.bbdb")), FileError);
    EXPECT_THROW(loaded.serialize(), FileError);
    EXPECT_THROW(loaded.clear(), FileError);
    EXPECT_THROW(Database::load(path, fixture.vocabulary, {Verification::kBeforeReturn}),
                 FileError);
  }
}

TEST(DatabaseMapped, DamagedDirectIndexNeverCrashesAndThenEveryCallThrows) {
  const Fixture fixture(400);
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  std::vector<std::uint8_t> bytes = fixture.database.serialize();
  const auto [offset, length] = bbdb_section(bytes, kDirectDataSection);
  std::mt19937_64 rng(4);
  for (std::size_t i = 0; i < length; ++i) bytes[offset + i] = static_cast<std::uint8_t>(rng());
  write_bytes(path, bytes);
  HeldChecks held;
  const Database loaded = Database::load(path, fixture.vocabulary);
  for (EntryId id = 0; id < loaded.next_entry_id(); ++id) {
    if (!fixture.database.contains(id)) continue;
    try {
      loaded.feature_vector(id);  // a vector, or FileError: never a crash
    } catch (const FileError& e) {
      EXPECT_NE(e.problem().find("direct index of entry"), std::string::npos) << e.what();
    }
  }
  held.release();
  try {
    loaded.wait_until_verified();
    FAIL() << "damage not found";
  } catch (const FileError& e) {
    EXPECT_NE(e.problem().find("'direct index'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(loaded.feature_vector(0), FileError);
}

TEST(DatabaseMapped, SavedOverItsOwnFileAndCompactedByRemovals) {
  Fixture fixture;
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  fixture.database.save(path);
  Database loaded = Database::load(path, fixture.vocabulary);
  // The save renames a new file over the mapped one, which stays readable.
  loaded.save(path, false);
  expect_same_answers(fixture.database, loaded, fixture);
  expect_same_answers(fixture.database, Database::load(path, fixture.vocabulary), fixture);
  // Removing half the entries compacts the mapped segment into memory.
  for (EntryId id = 0; id < fixture.database.next_entry_id(); id += 2) {
    if (!fixture.database.contains(id)) continue;
    fixture.database.remove(id);
    loaded.remove(id);
  }
  expect_same_answers(fixture.database, loaded, fixture);
  EXPECT_EQ(loaded.serialize(false), fixture.database.serialize(false));
  loaded.save(path, false);
  expect_same_answers(fixture.database, Database::load(path, fixture.vocabulary), fixture);
}

TEST(DatabaseMapped, JournalReplaysOverTheMappedFile) {
  Fixture fixture;
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  fixture.database.save(path);
  fixture.database.remove(1);
  fixture.database.add(fixture.queries[3]);
  fixture.database.save_incremental(path);
  // The removal waits for the check (it needs the entry's postings counted).
  const Database loaded = Database::load(path, fixture.vocabulary);
  expect_same_answers(fixture.database, loaded, fixture);
  EXPECT_EQ(loaded.serialize(), fixture.database.serialize());
}

TEST(DatabaseMapped, DestroyedOrClearedWhileItsCheckWaits) {
  const Fixture fixture(300);
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  fixture.database.save(path);
  HeldChecks held;
  { const Database loaded = Database::load(path); }  // stops the check: no hang
  Database loaded = Database::load(path);
  loaded.clear();
  EXPECT_EQ(loaded.size(), 0u);
  loaded.add(fixture.queries[0]);
  loaded.wait_until_verified();  // nothing left to check
  EXPECT_EQ(loaded.query(fixture.queries[0], 1).size(), 1u);
}

}  // namespace
}  // namespace binbow
