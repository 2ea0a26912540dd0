// Database::load maps a .bbdb file: a loaded database answers as the saved
// one, before and after the background check of its file; a damaged file
// never crashes a call, and once the check finds the damage every call
// throws FileError.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "core/background_check.h"
#include "support/test_support.h"

namespace binbow {
namespace {

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

// The bytes [offset, offset + length) of a section of the file's image.
std::pair<std::size_t, std::size_t> section_of(const std::vector<std::uint8_t>& file,
                                               std::uint32_t section) {
  std::uint64_t offset = 0, length = 0;
  std::memcpy(&offset, file.data() + 64 + 24 * section + 8, 8);
  std::memcpy(&length, file.data() + 64 + 24 * section + 16, 8);
  return {static_cast<std::size_t>(offset), static_cast<std::size_t>(length)};
}

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

TEST(DatabaseMapped, DamagedPostingsNeverCrashAndThenEveryCallThrows) {
  const Fixture fixture;
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  const std::vector<std::uint8_t> saved = fixture.database.serialize();
  const auto [offset, length] = section_of(saved, kPostingsSection);
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
  const auto [offset, length] = section_of(bytes, kDirectDataSection);
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
