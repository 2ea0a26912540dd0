// Incremental saves (the journal beside a .bbdb file): loading base + journal
// gives what a full save would; crashes at any step leave the old or the new
// database; damaged and hostile journals are refused clearly.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "../../fuzz/fuzz_targets.h"
#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "core/file_io.h"
#include "core/little_endian.h"
#include "database/database_journal.h"
#include "support/test_support.h"

namespace binbow {
namespace {

const Vocabulary& vocabulary() {
  static const Vocabulary built = test::clustered_vocabulary(5);
  return built;
}

// Adds an image of random descriptors, labelled every third time.
EntryId add_image(Database& database, std::mt19937_64& rng, std::size_t features = 30) {
  const DescriptorMatrix image = test::clustered_descriptors(features, 32, 40, 0.08, rng);
  const EntryId id = database.next_entry_id();
  return database.add(image.view(), id % 3 == 0 ? "image_" + std::to_string(id) : "");
}

std::vector<BowVector> probes() {
  std::mt19937_64 rng(11);
  std::vector<BowVector> bows;
  for (int i = 0; i < 12; ++i) {
    BowVector bow;
    vocabulary().transform(test::clustered_descriptors(30, 32, 40, 0.08, rng).view(), bow);
    bows.push_back(bow);
  }
  return bows;
}

// The same database: ids, labels, feature vectors, query results, and the
// bytes a full save writes.
void expect_same(const Database& expected, const Database& actual) {
  ASSERT_EQ(expected.next_entry_id(), actual.next_entry_id());
  EXPECT_EQ(expected.size(), actual.size());
  for (EntryId id = 0; id < expected.next_entry_id(); ++id) {
    ASSERT_EQ(expected.contains(id), actual.contains(id)) << "entry " << id;
    if (!expected.contains(id)) continue;
    EXPECT_EQ(expected.label(id), actual.label(id));
    if (expected.options().direct_index) {
      EXPECT_EQ(expected.feature_vector(id), actual.feature_vector(id));
    }
  }
  for (const BowVector& bow : probes())
    EXPECT_EQ(expected.query(bow, 1000), actual.query(bow, 1000));
  EXPECT_EQ(expected.serialize(), actual.serialize());
}

bool exists(const std::string& path) {
  return std::filesystem::exists(path);
}

std::uint64_t size_of(const std::string& path) {
  return std::filesystem::file_size(path);
}

struct Saved {
  test::TempDir dir;
  std::string path = dir.file("db.bbdb");
  std::string journal = Database::journal_path(path);
  Database database{vocabulary(), {true, 1}};
  std::mt19937_64 rng{3};

  explicit Saved(std::size_t entries = 40) {
    for (std::size_t i = 0; i < entries; ++i) add_image(database, rng);
    database.remove(7);
    database.save(path);
  }
};

TEST(DatabaseJournal, IsTheDatabaseFileNameWithJournalAppended) {
  EXPECT_EQ(Database::journal_path("dir/db.bbdb"), "dir/db.bbdb.journal");
}

TEST(DatabaseJournal, IncrementalSaveAppendsOnlyTheChanges) {
  Saved saved;
  const std::vector<std::uint8_t> base = test::read_file(saved.path);
  EXPECT_FALSE(exists(saved.journal));
  add_image(saved.database, saved.rng);
  add_image(saved.database, saved.rng);
  saved.database.remove(3);
  saved.database.set_label(4, "renamed.png");
  saved.database.save_incremental(saved.path);

  EXPECT_EQ(test::read_file(saved.path), base) << "the base is not rewritten";
  ASSERT_TRUE(exists(saved.journal));
  EXPECT_LT(size_of(saved.journal), base.size() / 5);
  expect_same(saved.database, Database::load(saved.path));

  const DatabaseJournalInfo info = Database::inspect_journal(saved.path);
  EXPECT_TRUE(info.present);
  EXPECT_FALSE(info.superseded);
  EXPECT_EQ(info.bytes, size_of(saved.journal));
  EXPECT_EQ(info.saves, 1u);
  EXPECT_EQ(info.added, 2u);
  EXPECT_EQ(info.removed, 1u);
  EXPECT_EQ(info.labels_set, 1u);
  EXPECT_EQ(info.cleared, 0u);
  EXPECT_EQ(info.torn_bytes, 0u);
}

TEST(DatabaseJournal, SavesAppendOneRecordEach) {
  Saved saved;
  std::uint64_t previous = 0;
  for (int save = 0; save < 4; ++save) {
    add_image(saved.database, saved.rng);
    saved.database.save_incremental(saved.path);
    EXPECT_GT(size_of(saved.journal), previous);
    previous = size_of(saved.journal);
  }
  saved.database.save_incremental(saved.path);  // nothing changed: nothing written
  EXPECT_EQ(size_of(saved.journal), previous);
  EXPECT_EQ(Database::inspect_journal(saved.path).saves, 4u);
  Database loaded = Database::load(saved.path);
  expect_same(saved.database, loaded);
  // The loaded database goes on appending to the same journal.
  add_image(loaded, saved.rng);
  loaded.remove(loaded.next_entry_id() - 1);
  add_image(loaded, saved.rng);
  loaded.save_incremental(saved.path);
  EXPECT_EQ(Database::inspect_journal(saved.path).saves, 5u);
  expect_same(loaded, Database::load(saved.path));
}

TEST(DatabaseJournal, ClearAndAddsAfterItReplay) {
  Saved saved;
  saved.database.clear();
  add_image(saved.database, saved.rng);
  add_image(saved.database, saved.rng);
  saved.database.save_incremental(saved.path);
  EXPECT_EQ(Database::inspect_journal(saved.path).cleared, 1u);
  expect_same(saved.database, Database::load(saved.path));
}

TEST(DatabaseJournal, FullSaveFoldsTheJournalIntoANewBase) {
  Saved saved;
  add_image(saved.database, saved.rng);
  saved.database.save_incremental(saved.path);
  ASSERT_TRUE(exists(saved.journal));
  saved.database.save(saved.path);
  EXPECT_FALSE(exists(saved.journal));
  EXPECT_FALSE(Database::inspect_journal(saved.path).present);
  expect_same(saved.database, Database::load(saved.path));
  // Incremental saves start a new journal on the new base.
  add_image(saved.database, saved.rng);
  saved.database.save_incremental(saved.path);
  EXPECT_EQ(Database::inspect_journal(saved.path).saves, 1u);
  expect_same(saved.database, Database::load(saved.path));
}

TEST(DatabaseJournal, FallsBackToAFullSaveWithoutItsBase) {
  test::TempDir dir;
  std::mt19937_64 rng(4);
  Database database(vocabulary(), {true, 1});
  for (int i = 0; i < 10; ++i) add_image(database, rng);
  // Never saved: a full save.
  const std::string path = dir.file("db.bbdb");
  database.save_incremental(path);
  EXPECT_TRUE(exists(path));
  EXPECT_FALSE(exists(Database::journal_path(path)));
  expect_same(database, Database::load(path));

  // Last saved elsewhere: a full save of this path.
  const std::string other = dir.file("other.bbdb");
  database.save(other);
  add_image(database, rng);
  database.save_incremental(path);
  EXPECT_FALSE(exists(Database::journal_path(path)));
  expect_same(database, Database::load(path));

  // The file was replaced behind the database's back: a save would
  // overwrite that change, and is refused.
  Database elsewhere = Database::load(path);
  add_image(elsewhere, rng);
  elsewhere.save(path);
  add_image(database, rng);
  EXPECT_THROW(database.save_incremental(path), WriteConflict);
  expect_same(elsewhere, Database::load(path));
  // Saved elsewhere since, the database replaces it as any new file.
  database.save(other);
  database.save_incremental(path);
  EXPECT_FALSE(exists(Database::journal_path(path)));
  expect_same(database, Database::load(path));

  // The base was removed: a full save.
  database.save(path);
  std::filesystem::remove(path);
  add_image(database, rng);
  database.save_incremental(path);
  expect_same(database, Database::load(path));
}

TEST(DatabaseJournal, AJournalPastAQuarterOfTheBaseIsCompacted) {
  Saved saved(20);
  const std::uint64_t limit = detail::journal_limit(size_of(saved.path));
  EXPECT_EQ(limit, std::uint64_t{1} << 20) << "small bases keep 1 MiB of journal";
  bool compacted = false;
  std::uint64_t previous = 0;
  for (int round = 0; round < 400 && !compacted; ++round) {
    for (int i = 0; i < 10; ++i) add_image(saved.database, saved.rng, 200);
    saved.database.save_incremental(saved.path);
    const std::uint64_t journal = exists(saved.journal) ? size_of(saved.journal) : 0;
    EXPECT_LE(journal, detail::journal_limit(size_of(saved.path)));
    compacted = journal < previous;
    previous = journal;
  }
  EXPECT_TRUE(compacted) << "the journal never went back to a full save";
  expect_same(saved.database, Database::load(saved.path));
}

TEST(DatabaseJournal, PendingChangesCountInMemoryUsage) {
  Saved saved;
  const std::size_t before = saved.database.memory_usage();
  for (int i = 0; i < 5; ++i) add_image(saved.database, saved.rng);
  Database untied(vocabulary(), {true, 1});
  std::mt19937_64 rng(3);
  for (int i = 0; i < 45; ++i) add_image(untied, rng);
  EXPECT_GT(saved.database.memory_usage(), untied.memory_usage()) << before;
  saved.database.save_incremental(saved.path);
  EXPECT_LE(saved.database.memory_usage(), untied.memory_usage() + 4096);
}

TEST(DatabaseJournal, WithoutDirectIndexOverWordIdsAndExternalVocabulary) {
  test::TempDir dir;
  std::mt19937_64 rng(8);
  {
    const std::string path = dir.file("plain.bbdb");
    Database database(vocabulary(), {false, 0});
    for (int i = 0; i < 10; ++i) add_image(database, rng);
    database.save(path, false);
    add_image(database, rng);
    database.remove(2);
    database.save_incremental(path, false);
    ASSERT_TRUE(exists(Database::journal_path(path)));
    expect_same(database, Database::load(path, vocabulary()));
  }
  {
    const std::string path = dir.file("words.bbdb");
    Database database = Database::over_word_ids(Scoring::kL1, {true, 0});
    const auto add_words = [&](WordId spread) {
      std::vector<BowEntry> entries;
      for (WordId w = 1 + rng() % 7; w < spread; w += 1 + static_cast<WordId>(rng() % 2000))
        entries.push_back({w, 0.01f + static_cast<float>(rng() % 100) / 100});
      std::vector<NodeId> nodes;
      for (const BowEntry& e : entries) nodes.push_back(e.word);
      database.add(BowVector(entries), FeatureVector::from_assignment(nodes.data(), nodes.size()));
    };
    for (int i = 0; i < 20; ++i) add_words(50'000);
    database.save(path);
    for (int i = 0; i < 5; ++i) add_words(100'000);  // the index grows its rows
    database.remove(3);
    database.save_incremental(path);
    ASSERT_TRUE(exists(Database::journal_path(path)));
    const Database loaded = Database::load(path);
    for (EntryId id = 0; id < database.next_entry_id(); ++id) {
      ASSERT_EQ(loaded.contains(id), database.contains(id));
      if (database.contains(id)) {
        EXPECT_EQ(loaded.feature_vector(id), database.feature_vector(id));
      }
    }
    std::vector<BowEntry> query;
    for (WordId w = 0; w < 100'000; w += 97) query.push_back({w, 1});
    EXPECT_EQ(loaded.query(BowVector(query), 100), database.query(BowVector(query), 100));
  }
}

// Random adds, removals, labels and clears, with incremental and full saves
// interleaved: after every save, loading gives the database in memory.
TEST(DatabaseJournal, RandomChangesAndSavesLoadAsTheDatabaseInMemory) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    test::TempDir dir;
    const std::string path = dir.file("db.bbdb");
    std::mt19937_64 rng(seed);
    Database database(vocabulary(), {true, 2});
    std::vector<EntryId> live;
    std::size_t incremental = 0;
    for (int step = 0; step < 300; ++step) {
      const unsigned action = rng() % 100;
      if (action < 45 || live.empty()) {
        live.push_back(add_image(database, rng, 5 + rng() % 40));
      } else if (action < 65) {
        const std::size_t i = rng() % live.size();
        database.remove(live[i]);
        live.erase(live.begin() + static_cast<std::ptrdiff_t>(i));
      } else if (action < 80) {
        database.set_label(live[rng() % live.size()],
                           rng() % 4 == 0 ? "" : "l" + std::to_string(step));
      } else if (action < 81) {
        database.clear();
        live.clear();
      } else if (action < 95) {
        database.save_incremental(path);
        ++incremental;
        expect_same(database, Database::load(path));
      } else if (action < 97) {
        database.save(path);
        expect_same(database, Database::load(path));
      } else {
        database = Database::load(path);  // unsaved changes are lost
        live.clear();
        for (EntryId id = 0; id < database.next_entry_id(); ++id)
          if (database.contains(id)) live.push_back(id);
      }
    }
    EXPECT_GT(incremental, 20u);
  }
}

// A save that fails between sealing the journal and replacing the base
// leaves the old base and its journal, which still load; once the new base
// is in place the sealed journal is ignored, wherever the save stopped.
TEST(DatabaseJournal, AFullSaveStoppedAtAnyStepLeavesALoadableDatabase) {
  Saved saved;
  add_image(saved.database, saved.rng);
  saved.database.save_incremental(saved.path);
  const Database committed = Database::load(saved.path);
  add_image(saved.database, saved.rng);  // not saved yet

  auto& calls = detail::replace_calls();
  const auto rename = calls.rename;
  calls.rename = [](const char*, const char*) {
    errno = EIO;
    return -1;
  };
  EXPECT_THROW(saved.database.save(saved.path), FileError);
  calls.rename = rename;
  // The journal is sealed for the base that never came; the old base and
  // its records still load.
  const std::vector<std::uint8_t> sealed = test::read_file(saved.journal);
  expect_same(committed, Database::load(saved.path));
  EXPECT_EQ(Database::inspect_journal(saved.path).saves, 1u);

  // The next incremental save is a full one (nothing may follow a seal).
  saved.database.save_incremental(saved.path);
  EXPECT_FALSE(exists(saved.journal));
  expect_same(saved.database, Database::load(saved.path));

  // Stopped after the rename, before the journal's removal: the sealed
  // journal names the new base and is ignored.
  test::write_file(saved.journal, sealed);
  const DatabaseJournalInfo info = Database::inspect_journal(saved.path);
  EXPECT_TRUE(info.superseded);
  Database loaded = Database::load(saved.path);
  expect_same(saved.database, loaded);
  // And the next incremental save replaces it with a journal of its own.
  add_image(loaded, saved.rng);
  loaded.save_incremental(saved.path);
  EXPECT_FALSE(Database::inspect_journal(saved.path).superseded);
  expect_same(loaded, Database::load(saved.path));
  // A full save removes a superseded journal too.
  test::write_file(saved.journal, sealed);
  loaded.save(saved.path);
  EXPECT_FALSE(exists(saved.journal));
}

TEST(DatabaseJournal, AJournalOfAnotherSaveIsRefused) {
  Saved saved;
  add_image(saved.database, saved.rng);
  saved.database.save_incremental(saved.path);
  const std::vector<std::uint8_t> old_journal = test::read_file(saved.journal);
  // An older save of the same path.
  add_image(saved.database, saved.rng);
  saved.database.save(saved.path);
  test::write_file(saved.journal, old_journal);
  for (const auto& attempt :
       {std::function<void()>([&] { Database::load(saved.path); }),
        std::function<void()>([&] { Database::inspect_journal(saved.path); })}) {
    try {
      attempt();
      FAIL() << "a journal of another save was accepted";
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), saved.journal);
      EXPECT_NE(e.problem().find("another save"), std::string::npos) << e.what();
    }
  }
  // Another database's journal.
  Saved other(41);
  test::write_file(other.journal, old_journal);
  EXPECT_THROW(Database::load(other.path), FileError);
  // A full save replaces what cannot be replayed.
  other.database.save(other.path);
  EXPECT_FALSE(exists(other.journal));
}

struct Journaled {
  Saved saved;
  Database after_first{vocabulary()};
  std::vector<std::uint8_t> bytes;
  std::size_t second_record = 0;

  Journaled() {
    add_image(saved.database, saved.rng);
    saved.database.set_label(2, "two");
    saved.database.save_incremental(saved.path);
    after_first = Database::load(saved.path);
    second_record = size_of(saved.journal);
    add_image(saved.database, saved.rng);
    saved.database.remove(5);
    saved.database.save_incremental(saved.path);
    bytes = test::read_file(saved.journal);
  }
  void write(const std::vector<std::uint8_t>& journal) const {
    test::write_file(saved.journal, journal);
  }
  // The journal with every CRC recomputed, as the fuzz target does.
  static std::vector<std::uint8_t> fixed(std::vector<std::uint8_t> journal) {
    fuzz::fix_journal_checksums(journal);
    return journal;
  }
};

void expect_refused(const std::string& path, const std::string& journal, const std::string& words) {
  try {
    Database::load(path);
    FAIL() << "accepted; expected: " << words;
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), journal);
    EXPECT_NE(e.problem().find(words), std::string::npos) << e.what();
  }
}

TEST(DatabaseJournal, AnAppendCutShortIsDropped) {
  const Journaled journaled;
  for (const std::size_t cut :
       {std::size_t{1}, std::size_t{10}, journaled.bytes.size() - journaled.second_record - 15,
        journaled.bytes.size() - journaled.second_record - 1}) {
    SCOPED_TRACE("cut " + std::to_string(cut));
    std::vector<std::uint8_t> torn(journaled.bytes.begin(),
                                   journaled.bytes.end() - static_cast<std::ptrdiff_t>(cut));
    journaled.write(torn);
    expect_same(journaled.after_first, Database::load(journaled.saved.path));
    EXPECT_EQ(Database::inspect_journal(journaled.saved.path).torn_bytes,
              torn.size() - journaled.second_record);
    // What a file system may leave: the append's first bytes, then zeros.
    const std::size_t kept = std::min(torn.size(), journaled.second_record + 5);
    std::fill(torn.begin() + static_cast<std::ptrdiff_t>(kept), torn.end(), 0);
    torn.resize(journaled.bytes.size(), 0);
    journaled.write(torn);
    expect_same(journaled.after_first, Database::load(journaled.saved.path));
  }
  // The next incremental save cuts the torn tail off before appending.
  Database loaded = Database::load(journaled.saved.path);
  std::mt19937_64 rng(6);
  add_image(loaded, rng);
  loaded.save_incremental(journaled.saved.path);
  EXPECT_EQ(Database::inspect_journal(journaled.saved.path).torn_bytes, 0u);
  expect_same(loaded, Database::load(journaled.saved.path));
}

TEST(DatabaseJournal, DamagedJournalsAreRefusedNamingTheOffset) {
  const Journaled journaled;
  const std::string& path = journaled.saved.path;
  const std::string& journal = journaled.saved.journal;
  const auto damaged = [&](std::size_t at) {
    std::vector<std::uint8_t> bytes = journaled.bytes;
    bytes[at] ^= 0x10;
    return bytes;
  };
  journaled.write(damaged(32 + 16 + 5));  // the first record's payload
  expect_refused(path, journal, "damaged record at offset 32");
  journaled.write(damaged(33));  // the first record's header
  expect_refused(path, journal, "damaged record header at offset 32");
  journaled.write(damaged(3));
  expect_refused(path, journal, "not a binbow database journal");
  journaled.write(damaged(20));
  expect_refused(path, journal, "header checksum mismatch");
  journaled.write({journaled.bytes.begin(), journaled.bytes.begin() + 20});
  expect_refused(path, journal, "truncated");
  std::vector<std::uint8_t> newer = journaled.bytes;
  detail::store_le<std::uint32_t>(newer.data() + 8, 3);
  journaled.write(Journaled::fixed(newer));
  expect_refused(path, journal, "unsupported journal version 3");
  // Version 1 could not tell its base from another save of the same size.
  std::vector<std::uint8_t> older = journaled.bytes;
  detail::store_le<std::uint32_t>(older.data() + 8, 1);
  journaled.write(Journaled::fixed(older));
  expect_refused(path, journal, "compact it with that binbow");
  journaled.write({});
  EXPECT_THROW(Database::load(path), FileError);
}

// Records whose CRCs are right but whose changes are not: each refused with
// the record's offset, never applied in part unnoticed.
TEST(DatabaseJournal, HostileRecordsAreRefused) {
  const Journaled journaled;
  const std::string& path = journaled.saved.path;
  const std::string& journal = journaled.saved.journal;
  // The first record: kind, then the add (type 1) of entry 40 (one byte).
  const std::size_t payload = 32 + 16;
  ASSERT_EQ(journaled.bytes[payload], 1);
  ASSERT_EQ(journaled.bytes[payload + 1], 1);
  ASSERT_EQ(journaled.bytes[payload + 2], 40);
  const auto with = [&](std::size_t at, std::uint8_t value) {
    std::vector<std::uint8_t> bytes = journaled.bytes;
    bytes[at] = value;
    journaled.write(Journaled::fixed(bytes));
  };
  with(payload + 2, 41);
  expect_refused(path, journal, "record at offset 32: adds entry 41 where the next entry id is 40");
  with(payload, 9);
  expect_refused(path, journal, "unknown record kind 9");
  with(payload + 1, 7);
  expect_refused(path, journal, "unknown change type 7");
  with(payload + 1, 2);  // remove entry 40, which does not exist; then garbage
  expect_refused(path, journal, "record at offset 32");
  std::vector<std::uint8_t> long_label = journaled.bytes;
  long_label[payload + 3] = 0xFF;  // a label of 16,383 bytes, longer than the record
  long_label.insert(long_label.begin() + static_cast<std::ptrdiff_t>(payload) + 4, 0x7F);
  detail::store_le<std::uint64_t>(long_label.data() + 32,
                                  detail::load_le<std::uint64_t>(long_label.data() + 32) + 1);
  journaled.write(Journaled::fixed(long_label));
  expect_refused(path, journal, "label length 16383 runs past the record");
  // The second record removes entry 5: make it entry 7, removed before.
  const std::size_t second = journaled.second_record + 16;
  std::vector<std::uint8_t> bytes = journaled.bytes;
  const std::uint8_t removal[] = {2, 5};
  const auto remove = std::find_end(bytes.begin() + static_cast<std::ptrdiff_t>(second),
                                    bytes.end(), std::begin(removal), std::end(removal));
  ASSERT_NE(remove, bytes.end());
  ASSERT_EQ(*(remove + 1), 5);
  *(remove + 1) = 7;
  journaled.write(Journaled::fixed(bytes));
  expect_refused(
      path, journal,
      "record at offset " + std::to_string(journaled.second_record) + ": Database::remove");
}

}  // namespace
}  // namespace binbow
