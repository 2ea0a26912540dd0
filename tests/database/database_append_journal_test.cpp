// Database::append_journal: save_incremental's append without its full save,
// for callers that save the whole database under another name instead.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>
#include <string>

#include "binbow/database.h"
#include "support/test_support.h"

namespace binbow {
namespace {

namespace fs = std::filesystem;

void add_image(Database& database, std::mt19937_64& rng, const std::string& label = "") {
  database.add(test::clustered_descriptors(30, 32, 40, 0.08, rng).view(), label);
}

TEST(DatabaseAppendJournal, AppendsLikeSaveIncrementalOrWritesNothing) {
  test::TempDir dir;
  const std::string path = dir.file("db.bbdb");
  const std::string journal = Database::journal_path(path);
  const Vocabulary vocabulary = test::clustered_vocabulary(5);
  Database database(vocabulary);
  std::mt19937_64 rng(3);
  for (int i = 0; i < 4; ++i) add_image(database, rng);
  EXPECT_FALSE(database.append_journal(path));  // never saved there
  EXPECT_FALSE(fs::exists(path));
  database.save(path);
  const auto base = test::read_file(path);
  EXPECT_TRUE(database.append_journal(path));  // nothing to append
  EXPECT_FALSE(fs::exists(journal));
  add_image(database, rng, "fifth");
  ASSERT_TRUE(database.append_journal(path));
  const auto appended = test::read_file(journal);
  EXPECT_FALSE(appended.empty());
  EXPECT_EQ(test::read_file(path), base);
  EXPECT_EQ(Database::load(path).label(4), "fifth");

  // A change the journal cannot take (past its 1 MiB floor): nothing is
  // written, the changes stay for the full save.
  add_image(database, rng, std::string(std::size_t{1} << 20, 'x'));
  EXPECT_FALSE(database.append_journal(path));
  EXPECT_EQ(test::read_file(path), base);
  EXPECT_EQ(test::read_file(journal), appended);
  EXPECT_FALSE(database.append_journal(dir.file("other.bbdb")));
  const std::string renamed = dir.file("db.gen2.bbdb");
  database.save(renamed);
  EXPECT_EQ(test::read_file(journal), appended);  // the old files are left alone
  const Database loaded = Database::load(renamed);
  EXPECT_EQ(loaded.next_entry_id(), 6u);
  EXPECT_EQ(loaded.label(5).size(), std::size_t{1} << 20);
  add_image(database, rng, "seventh");
  EXPECT_TRUE(database.append_journal(renamed));  // tied to the new file
  EXPECT_EQ(Database::load(renamed).label(6), "seventh");
}

}  // namespace
}  // namespace binbow
