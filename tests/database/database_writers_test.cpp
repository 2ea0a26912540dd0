// Database files shared by writers and readers: one writer at a time
// (DatabaseLock), a save never overwrites a change it did not load, a
// journal replays only over its own base, a link and its target are one
// database, what dead saves leave is swept, readers see committed states.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "../../fuzz/fuzz_targets.h"
#include "binbow/database.h"
#include "binbow/error.h"
#include "core/file_io.h"
#include "core/little_endian.h"
#include "database/database_journal.h"
#include "support/test_support.h"

namespace binbow {
namespace {

// A database over word ids: entry i holds words {i, i + 1} at `weight`.
Database over_words(std::size_t entries, float weight = 0.5f) {
  Database database = Database::over_word_ids(Scoring::kL1, {false, 0});
  for (std::size_t i = 0; i < entries; ++i) {
    const auto word = static_cast<WordId>(i);
    database.add(BowVector(std::vector<BowEntry>{{word, weight}, {word + 1, 1 - weight}}));
  }
  return database;
}

BowVector image(WordId word) {
  return BowVector(std::vector<BowEntry>{{word, 0.25f}, {word + 7, 0.75f}});
}

std::string message_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& words) {
  return text.find(words) != std::string::npos;
}

TEST(DatabaseWriters, BasesOfTheSameSizeHaveDifferentIds) {
  test::TempDir dir;
  over_words(5, 0.5f).save(dir.file("a.bbdb"));
  over_words(5, 0.25f).save(dir.file("b.bbdb"));
  ASSERT_EQ(std::filesystem::file_size(dir.file("a.bbdb")),
            std::filesystem::file_size(dir.file("b.bbdb")));
  detail::BaseId a, b;
  ASSERT_TRUE(detail::read_base_id(dir.file("a.bbdb"), a));
  ASSERT_TRUE(detail::read_base_id(dir.file("b.bbdb"), b));
  EXPECT_NE(a, b);
}

TEST(DatabaseWriters, AJournalOfAnotherDatabaseOfTheSameSizeIsRefused) {
  test::TempDir dir;
  const std::string a = dir.file("a.bbdb"), b = dir.file("b.bbdb");
  Database first = over_words(5, 0.5f);
  first.save(a);
  over_words(5, 0.25f).save(b);
  first.add(image(20));
  first.save_incremental(a);
  std::filesystem::copy_file(Database::journal_path(a), Database::journal_path(b));
  const std::string message = message_of([&] { Database::load(b); });
  EXPECT_TRUE(contains(message, "another save")) << message;
}

// A full save killed after its rename and before it removed the journal:
// the new base, of the old one's size, with the journal sealed for it.
TEST(DatabaseWriters, ASealedJournalBesideANewBaseOfTheSameSizeIsIgnored) {
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  Database database = over_words(6);
  database.set_label(0, "y");
  database.save(path);
  const auto base_size = std::filesystem::file_size(path);
  // A removal makes the base smaller; a longer label as long as what it
  // saved gives the new base the old size.
  Database probe = Database::load(path);
  probe.remove(2);
  const auto removed_size = probe.serialize().size();
  ASSERT_LT(removed_size, base_size);
  database.remove(2);
  database.set_label(0, std::string(base_size - removed_size + 1, 'x'));
  database.save_incremental(path);
  std::vector<std::uint8_t> journal = test::read_file(Database::journal_path(path));
  database.save(path);
  ASSERT_EQ(std::filesystem::file_size(path), base_size);
  detail::BaseId sealed;
  ASSERT_TRUE(detail::read_base_id(path, sealed));
  const std::size_t at = journal.size();
  journal.resize(at + detail::kJournalRecordHeaderSize + 13);
  detail::store_le<std::uint64_t>(journal.data() + at, 13);
  journal[at + detail::kJournalRecordHeaderSize] = 2;  // a sealing record
  detail::store_le<std::uint64_t>(journal.data() + at + detail::kJournalRecordHeaderSize + 1,
                                  sealed.size);
  detail::store_le<std::uint32_t>(journal.data() + at + detail::kJournalRecordHeaderSize + 9,
                                  sealed.checksum);
  fuzz::fix_journal_checksums(journal);
  test::write_file(Database::journal_path(path), journal);
  const Database loaded = Database::load(path);
  EXPECT_FALSE(loaded.contains(2));
  EXPECT_EQ(loaded.label(0), database.label(0));
  EXPECT_EQ(loaded.serialize(), database.serialize());
}

TEST(DatabaseWriters, ARecordOfAnotherBaseIsNoRecordOfThisJournal) {
  test::TempDir dir;
  const std::string a = dir.file("a.bbdb"), b = dir.file("b.bbdb");
  Database first = over_words(5, 0.5f), second = over_words(5, 0.25f);
  first.save(a);
  second.save(b);
  first.add(image(20));
  first.save_incremental(a);
  second.add(image(30));
  second.save_incremental(b);
  // b's record appended to a's journal is damage, not a change of a.
  std::vector<std::uint8_t> journal = test::read_file(Database::journal_path(a));
  const std::vector<std::uint8_t> other = test::read_file(Database::journal_path(b));
  journal.insert(journal.end(), other.begin() + detail::kJournalHeaderSize, other.end());
  test::write_file(Database::journal_path(a), journal);
  const std::string message = message_of([&] { Database::load(a); });
  EXPECT_TRUE(contains(message, "damaged record header")) << message;
}

TEST(DatabaseWriters, ALockHeldByAnotherProcessStopsSavesAndNamesIt) {
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  Database database = over_words(4);
  database.save(path);
  int ready[2], release[2];
  ASSERT_EQ(::pipe(ready), 0);
  ASSERT_EQ(::pipe(release), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    {
      const DatabaseLock lock(path);
      char byte = 1;
      (void)!::write(ready[1], &byte, 1);
      (void)!::read(release[0], &byte, 1);
    }
    ::_exit(0);
  }
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  database.add(image(10));
  for (const auto& save : {std::function<void()>([&] { database.save_incremental(path); }),
                           std::function<void()>([&] { database.save(path); }),
                           std::function<void()>([&] { DatabaseLock lock(path, 0.2); })}) {
    try {
      save();
      ADD_FAILURE() << "a second writer went ahead";
    } catch (const WriteConflict& e) {
      EXPECT_TRUE(contains(e.problem(), "process " + std::to_string(child))) << e.what();
      EXPECT_TRUE(contains(e.problem(), DatabaseLock::lock_path(path))) << e.what();
    }
  }
  EXPECT_EQ(Database::load(path).next_entry_id(), 4u);  // nothing was written
  // A writer that waits goes ahead once the holder is done.
  std::thread releaser([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    (void)!::write(release[1], &byte, 1);
  });
  {
    const DatabaseLock lock(path, 30);
    database.save_incremental(path);
  }
  releaser.join();
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_EQ(Database::load(path).next_entry_id(), 5u);
  for (int fd : {ready[0], ready[1], release[0], release[1]}) ::close(fd);
}

TEST(DatabaseWriters, TheLockIsTheThreadsAndNestsInIt) {
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  const DatabaseLock outer(path);
  {
    const DatabaseLock inner(path);  // the same thread: nested
    over_words(2).save(path);
  }
  std::string message;
  std::thread other([&] { message = message_of([&] { DatabaseLock lock(path, 0.05); }); });
  other.join();
  EXPECT_TRUE(contains(message, "another thread of this process")) << message;
}

// Two writers that loaded the same file: the second save would overwrite
// the first's change, and is refused instead, incremental or full.
TEST(DatabaseWriters, ASaveNeverOverwritesAChangeItDidNotLoad) {
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  over_words(4).save(path);
  for (const bool full : {false, true}) {
    for (const bool journal_first : {false, true}) {
      SCOPED_TRACE(std::string(full ? "full" : "incremental") +
                   (journal_first ? ", after a journal" : ""));
      over_words(4).save(path);
      if (journal_first) {
        Database earlier = Database::load(path);
        earlier.add(image(40));
        earlier.save_incremental(path);
      }
      Database first = Database::load(path), second = Database::load(path);
      first.add(image(50));
      first.save_incremental(path);
      second.add(image(60));
      const std::string message = message_of([&] {
        if (full)
          second.save(path);
        else
          second.save_incremental(path);
      });
      EXPECT_TRUE(contains(message, "another writer saved the database")) << message;
      const Database loaded = Database::load(path);
      ASSERT_EQ(loaded.next_entry_id(), first.next_entry_id());
      EXPECT_EQ(loaded.serialize(), first.serialize());
      // Loaded again, the second writer saves on top of the first.
      Database again = Database::load(path);
      again.add(image(60));
      again.save_incremental(path);
      EXPECT_EQ(Database::load(path).next_entry_id(), first.next_entry_id() + 1);
    }
  }
}

TEST(DatabaseWriters, ALinkAndItsTargetAreOneDatabase) {
  test::TempDir dir;
  const std::string real = dir.file("real.bbdb"), link = dir.file("link.bbdb");
  over_words(4).save(real);
  std::filesystem::create_symlink("real.bbdb", link);
  Database through_link = Database::load(link);
  through_link.add(image(10));
  through_link.save_incremental(link);
  EXPECT_TRUE(std::filesystem::exists(Database::journal_path(real)));
  EXPECT_FALSE(std::filesystem::exists(Database::journal_path(link)));
  Database through_target = Database::load(real);
  EXPECT_EQ(through_target.next_entry_id(), 5u);
  through_target.add(image(20));
  through_target.save_incremental(real);
  // The link's database is tied to the same file: this is a conflict, not
  // a silent fork.
  through_link.add(image(30));
  EXPECT_THROW(through_link.save_incremental(link), WriteConflict);
  Database compacted = Database::load(link);
  EXPECT_EQ(compacted.next_entry_id(), 6u);
  compacted.save(link);  // a full save through the link
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_FALSE(std::filesystem::exists(Database::journal_path(real)));
  EXPECT_EQ(Database::load(real).next_entry_id(), 6u);
  EXPECT_EQ(Database::load(link).serialize(), Database::load(real).serialize());
}

TEST(DatabaseWriters, IncrementalSavesSweepWhatDeadSavesLeft) {
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  Database database = over_words(4);
  database.save(path);
  const std::string temporary = path + ".tmp-Ab12Cd";
  test::write_file(temporary, std::vector<std::uint8_t>(100, 7));
  std::filesystem::create_hard_link(path, path + ".old-Ef34Gh");
  database.add(image(10));
  database.save_incremental(path);
  EXPECT_FALSE(std::filesystem::exists(temporary));
  EXPECT_FALSE(std::filesystem::exists(path + ".old-Ef34Gh"));
  EXPECT_EQ(Database::load(path).next_entry_id(), 5u);
}

TEST(DatabaseWriters, AJournalLongerThanItsBaseAllowsIsRefusedWithoutReadingIt) {
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  Database database = over_words(4);
  database.save(path);
  database.add(image(10));
  database.save_incremental(path);
  // Zeros past any record a save could have left: 64 MiB over a 1 MiB limit.
  std::filesystem::resize_file(Database::journal_path(path), std::uint64_t{64} << 20);
  const std::string message = message_of([&] { Database::load(path); });
  EXPECT_TRUE(contains(message, "can hold: it is damaged")) << message;
  EXPECT_TRUE(contains(message_of([&] { Database::inspect_journal(path); }), "damaged"));
}

TEST(DatabaseWriters, AFailureAfterTheCommitIsAWarningAndTheSaveStands) {
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  Database database = over_words(4);
  database.save(path);
  database.add(image(10));
  std::vector<std::string> warnings;
  set_warning_handler([&](const std::string& message) { warnings.push_back(message); });
  detail::ReplaceCalls& calls = detail::replace_calls();
  const detail::ReplaceCalls saved = calls;
  // The previous version's backup cannot be removed once the new file is in.
  calls.unlink = [](const char* name) -> int {
    if (std::string(name).find(".old-") != std::string::npos) {
      errno = EIO;
      return -1;
    }
    return ::unlink(name);
  };
  EXPECT_NO_THROW(database.save(path));
  calls = saved;
  set_warning_handler(nullptr);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(contains(warnings[0], "saved, but its previous version stays")) << warnings[0];
  EXPECT_EQ(Database::load(path).next_entry_id(), 5u);
}

// Readers take no lock: while a writer alternates incremental and full
// saves, every load gives a state some save committed.
TEST(DatabaseWriters, LoadsDuringSavesGiveCommittedStates) {
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  Database writer = over_words(4);
  writer.save(path);
  std::atomic<bool> done{false};
  std::atomic<EntryId> committed{4};
  std::thread saving([&] {
    for (int i = 0; i < 120; ++i) {
      writer.add(image(static_cast<WordId>(i % 50)));
      if (i % 5 == 4)
        writer.save(path);
      else
        writer.save_incremental(path);
      committed = writer.next_entry_id();
    }
    done = true;
  });
  int loads = 0;
  std::string failure;
  while (!done && failure.empty()) {
    const EntryId before = committed;
    try {
      const EntryId loaded = Database::load(path).next_entry_id();
      if (loaded < before || loaded > committed + 1)
        failure = "loaded " + std::to_string(loaded) + " entries, committed " +
                  std::to_string(before) + " to " + std::to_string(committed);
    } catch (const std::exception& e) {
      failure = e.what();
    }
    ++loads;
  }
  saving.join();
  EXPECT_EQ(failure, "") << "after " << loads << " loads";
  EXPECT_EQ(Database::load(path).next_entry_id(), 124u);
}

}  // namespace
}  // namespace binbow
