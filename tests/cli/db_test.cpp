// `binbow db build`, `binbow db query` and `binbow info` on a database, on
// the real rtabmap-samples corridor; and database queries on real ORB
// features against brute force for every scoring.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/formats.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::run_cli;
using test::samples_folder;
using test::shared_data;
using test::TempDir;

// The corridor's 84 frames in a database at `database`, on the small
// vocabulary.
void build_corridor_database(const std::string& database) {
  std::string output;
  ASSERT_EQ(run_cli("db build --vocab '" + shared_data("kimera-small-voc/small_voc.yml.gz") +
                        "' -o '" + database + "' '" + samples_folder() + "'",
                    &output),
            0)
      << output;
}

TEST(CliDb, BuildQueryInfo) {
  TempDir dir;
  const std::string vocabulary = shared_data("kimera-small-voc/small_voc.yml.gz");
  const std::string folder = samples_folder();
  const std::string database = dir.file("corridor.bbdb");
  std::string output;
  ASSERT_EQ(run_cli("db build --vocab '" + vocabulary + "' -o '" + database + "' '" + folder + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("84 entries"), std::string::npos) << output;

  ASSERT_EQ(run_cli("info '" + database + "'", &output), 0) << output;
  EXPECT_NE(output.find("kind: database\n"), std::string::npos) << output;
  EXPECT_NE(output.find("entries: 84\n"), std::string::npos) << output;
  EXPECT_NE(output.find("vocabulary: k=9 L=3"), std::string::npos) << output;

  // Frame 54 revisits frame 14 (ground truth): itself first, its old view next.
  ASSERT_EQ(run_cli("db query '" + database + "' '" + folder + "/54.jpg' --top 3", &output), 0)
      << output;
  EXPECT_EQ(output.find("query: " + folder + "/54.jpg\nrank\tentry\tfile\tscore\n"), 0u) << output;
  EXPECT_NE(output.find("1\t53\t" + folder + "/54.jpg\t1.000000\n"), std::string::npos) << output;
  EXPECT_NE(output.find("2\t13\t" + folder + "/14.jpg\t"), std::string::npos) << output;
  EXPECT_EQ(std::count(output.begin(), output.end(), '\n'), 5) << output;
}

// One table per query image, whether the images are named, in a folder, in
// a list or sampled with the image-source options.
TEST(CliDb, QueriesSeveralImagesOneTableEach) {
  TempDir dir;
  const std::string folder = samples_folder();
  const std::string database = dir.file("corridor.bbdb");
  ASSERT_NO_FATAL_FAILURE(build_corridor_database(database));
  std::string output;
  ASSERT_EQ(
      run_cli("db query '" + database + "' '" + folder + "/54.jpg' '" + folder + "/14.jpg' --top 2",
              &output),
      0)
      << output;
  const std::string first = "query: " + folder + "/54.jpg\nrank\tentry\tfile\tscore\n1\t53\t" +
                            folder + "/54.jpg\t1.000000\n2\t13\t" + folder + "/14.jpg\t";
  EXPECT_EQ(output.find(first), 0u) << output;
  const std::string second = "\n\nquery: " + folder + "/14.jpg\nrank\tentry\tfile\tscore\n1\t13\t" +
                             folder + "/14.jpg\t1.000000\n2\t52\t" + folder + "/53.jpg\t";
  EXPECT_NE(output.find(second), std::string::npos) << output;

  ASSERT_EQ(run_cli("db query '" + database + "' '" + folder + "' --stride 10 --top 1", &output), 0)
      << output;
  std::size_t tables = 0;
  for (int frame = 1; frame <= 84; frame += 10) {
    const std::string name = folder + "/" + std::to_string(frame) + ".jpg";
    EXPECT_NE(output.find("query: " + name + "\nrank\tentry\tfile\tscore\n1\t" +
                          std::to_string(frame - 1) + "\t" + name + "\t1.000000\n"),
              std::string::npos)
        << name << "\n"
        << output;
    ++tables;
  }
  EXPECT_EQ(static_cast<std::size_t>(std::count(output.begin(), output.end(), '\n')),
            tables * 3 + tables - 1)
      << output;
}

// --fast reports exact scores, and on the real corridor (a small vocabulary:
// frames share most words) the same top 5 as the exact query for every frame.
TEST(CliDb, FastQueriesGiveTheExactTablesOnTheCorridor) {
  TempDir dir;
  const std::string folder = samples_folder();
  const std::string database = dir.file("corridor.bbdb");
  ASSERT_NO_FATAL_FAILURE(build_corridor_database(database));
  std::string exact, fast;
  ASSERT_EQ(run_cli("db query '" + database + "' '" + folder + "' --top 5", &exact), 0) << exact;
  ASSERT_EQ(run_cli("db query --fast '" + database + "' '" + folder + "' --top 5", &fast), 0)
      << fast;
  std::size_t tables = 0;
  for (std::size_t at = exact.find("query: "); at != std::string::npos;
       at = exact.find("query: ", at + 1))
    ++tables;
  EXPECT_EQ(tables, 84u);
  EXPECT_TRUE(fast == exact) << "fast:\n" << fast.substr(0, 2000);
}

// Each query's result rows ("entry\tfile\tscore") of a db query output.
std::vector<std::vector<std::string>> result_rows(const std::string& output) {
  std::vector<std::vector<std::string>> tables;
  std::size_t start = 0;
  for (std::size_t end; (end = output.find('\n', start)) != std::string::npos; start = end + 1) {
    const std::string line = output.substr(start, end - start);
    if (line.rfind("query: ", 0) == 0) {
      tables.emplace_back();
    } else if (!tables.empty() && !line.empty() && line.rfind("rank\t", 0) != 0) {
      tables.back().push_back(line.substr(line.find('\t') + 1));
    }
  }
  return tables;
}

// The fast-mode tuning reaches the query: as many candidates as entries give
// the exact tables; one candidate from few postings gives other tables on the
// corridor, each row with its exact score.
TEST(CliDb, FastTuningOptionsReachTheQuery) {
  TempDir dir;
  const std::string folder = samples_folder();
  const std::string database = dir.file("corridor.bbdb");
  ASSERT_NO_FATAL_FAILURE(build_corridor_database(database));
  const std::string query = "db query '" + database + "' '" + folder + "' ";
  std::string exact, every_entry, whole_share, few, all_results;
  ASSERT_EQ(run_cli(query + "--top 5", &exact), 0) << exact;
  ASSERT_EQ(
      run_cli(query + "--top 5 --fast --fast-candidates 84 --fast-min-postings 0", &every_entry), 0)
      << every_entry;
  ASSERT_EQ(run_cli(query + "--top 5 --fast --fast-candidates 1 --fast-candidate-share 1 "
                            "--fast-min-postings 0",
                    &whole_share),
            0)
      << whole_share;
  EXPECT_TRUE(every_entry == exact) << every_entry.substr(0, 2000);
  EXPECT_TRUE(whole_share == exact) << whole_share.substr(0, 2000);

  ASSERT_EQ(run_cli(query + "--top 5 --fast --fast-candidates 1 --fast-min-postings 0", &few), 0)
      << few;
  ASSERT_EQ(run_cli(query + "--top 84", &all_results), 0) << all_results;
  const auto few_tables = result_rows(few);
  const auto exact_tables = result_rows(exact);
  const auto all_tables = result_rows(all_results);
  ASSERT_EQ(few_tables.size(), 84u);
  ASSERT_EQ(exact_tables.size(), 84u);
  ASSERT_EQ(all_tables.size(), 84u);
  std::size_t differing = 0;
  for (std::size_t q = 0; q < few_tables.size(); ++q) {
    EXPECT_EQ(few_tables[q].size(), exact_tables[q].size()) << q;  // 0 for a featureless frame
    if (few_tables[q] != exact_tables[q]) ++differing;
    for (const std::string& row : few_tables[q])
      EXPECT_NE(std::find(all_tables[q].begin(), all_tables[q].end(), row), all_tables[q].end())
          << "query " << q << ": " << row;
  }
  EXPECT_GT(differing, 0u) << few.substr(0, 2000);
}

// Without --vocab, db build uses the bundled vocabulary of --descriptor, as
// detect-loops does.
TEST(CliDb, BuildDefaultsToTheBundledVocabulary) {
  TempDir dir;
  const std::string folder = samples_folder();
  const std::string database = dir.file("d.bbdb");
  std::string output;
  ASSERT_EQ(run_cli("db build --descriptor brief -o '" + database + "' '" + folder + "/1.jpg' '" +
                        folder + "/2.jpg'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("2 entries"), std::string::npos) << output;
  EXPECT_NE(output.find("brief_default.bbw"), std::string::npos) << output;
  ASSERT_EQ(run_cli("info '" + database + "'", &output), 0) << output;
  const Vocabulary bundled = load_vocabulary(test::source_path("data/vocab/brief_default.bbw"));
  char checksum[16];
  std::snprintf(checksum, sizeof checksum, "%08x", bundled.checksum());
  EXPECT_NE(output.find(std::string("vocabulary_checksum: ") + checksum + "\n"), std::string::npos)
      << output;
}

// A truncated JPEG among the images stops db build and db query, unless
// --skip-unreadable: then it is an entry without features, so the entries
// keep the images' order (db add likewise), and queries skip it.
TEST(CliDb, SkipUnreadableGoesOnWithoutTheDamagedImage) {
  TempDir dir;
  const std::string folder = samples_folder();
  std::vector<std::uint8_t> bytes = test::read_file(folder + "/2.jpg");
  bytes.resize(bytes.size() / 2);
  const std::string damaged = dir.file("2.jpg");
  test::write_file(damaged, bytes);
  const std::string images = "'" + folder + "/1.jpg' '" + damaged + "' '" + folder + "/3.jpg'";
  const std::string database = dir.file("d.bbdb");
  std::string output;
  EXPECT_EQ(run_cli("db build -o '" + database + "' " + images, &output), 1) << output;
  EXPECT_NE(output.find("binbow: error: " + damaged + ": damaged JPEG"), std::string::npos)
      << output;
  ASSERT_EQ(run_cli("db build --skip-unreadable -o '" + database + "' " + images, &output), 0)
      << output;
  EXPECT_NE(output.find("binbow: warning: " + damaged + ": damaged JPEG"), std::string::npos)
      << output;
  EXPECT_NE(output.find("skipped frames: 1\n"), std::string::npos) << output;
  EXPECT_NE(output.find("3 entries"), std::string::npos) << output;
  const Database built = Database::load(database);
  EXPECT_EQ(built.label(1), damaged);
  EXPECT_EQ(built.label(2), folder + "/3.jpg");

  EXPECT_EQ(run_cli("db query '" + database + "' " + images, &output), 1) << output;
  ASSERT_EQ(run_cli("db query --skip-unreadable '" + database + "' " + images, &output), 0)
      << output;
  EXPECT_NE(output.find("query: " + folder + "/3.jpg\n"), std::string::npos) << output;
  EXPECT_EQ(output.find("query: " + damaged), std::string::npos) << output;
  EXPECT_NE(output.find("skipped frames: 1\n"), std::string::npos) << output;

  EXPECT_EQ(run_cli("db add '" + database + "' '" + damaged + "'", &output), 1) << output;
  ASSERT_EQ(run_cli("db add --skip-unreadable '" + database + "' '" + damaged + "'", &output), 0)
      << output;
  EXPECT_NE(output.find("added 3\t" + damaged + "\n"), std::string::npos) << output;
}

TEST(CliDb, AddsAndRemovesEntriesInPlace) {
  TempDir dir;
  const std::string folder = samples_folder();
  const std::string database = dir.file("d.bbdb");
  const std::string vocabulary = shared_data("kimera-small-voc/small_voc.yml.gz");
  std::string output;
  ASSERT_EQ(run_cli("db build --external-vocab --vocab '" + vocabulary + "' -o '" + database +
                        "' '" + folder + "/1.jpg' '" + folder + "/2.jpg'",
                    &output),
            0)
      << output;

  const std::string list = dir.file("more.txt");
  test::write_file(list, {'5', '4', '.', 'j', 'p', 'g', '\n'});
  std::filesystem::copy_file(folder + "/54.jpg", dir.file("54.jpg"));
  ASSERT_EQ(run_cli("db add '" + database + "' --vocab '" + vocabulary + "' '" + folder +
                        "/14.jpg' '" + list + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("added 2\t" + folder + "/14.jpg\nadded 3\t" + dir.file("54.jpg") + "\n"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find(database + ": 2 entries added, 4 entries\n"), std::string::npos) << output;
  ASSERT_EQ(run_cli("info '" + database + "'", &output), 0) << output;
  EXPECT_NE(output.find("entries: 4\n"), std::string::npos) << output;
  EXPECT_NE(output.find("vocabulary_included: no\n"), std::string::npos) << output;
  // The new entries went to the journal; the file itself was not rewritten.
  EXPECT_NE(output.find("journal: "), std::string::npos) << output;
  EXPECT_NE(output.find(" bytes, 1 saves: 2 entries added, 0 removed, 0 labels set\n"),
            std::string::npos)
      << output;
  EXPECT_EQ(Database::inspect(database, false).entries, 2u);
  ASSERT_EQ(run_cli("db query '" + database + "' --vocab '" + vocabulary + "' '" + folder +
                        "/54.jpg' --top 2",
                    &output),
            0)
      << output;
  EXPECT_NE(
      output.find("1\t3\t" + dir.file("54.jpg") + "\t1.000000\n2\t2\t" + folder + "/14.jpg\t"),
      std::string::npos)
      << output;

  ASSERT_EQ(run_cli("db remove '" + database + "' --vocab '" + vocabulary + "' 0 3", &output), 0)
      << output;
  EXPECT_NE(output.find("removed 0\t" + folder + "/1.jpg\nremoved 3\t" + dir.file("54.jpg") + "\n" +
                        database + ": 2 entries removed, 2 entries\n"),
            std::string::npos)
      << output;
  ASSERT_EQ(run_cli("info '" + database + "'", &output), 0) << output;
  EXPECT_NE(output.find("entries: 2\nnext_entry_id: 4\n"), std::string::npos) << output;
  EXPECT_NE(output.find(" bytes, 2 saves: 2 entries added, 2 removed, 0 labels set\n"),
            std::string::npos)
      << output;
  // --compact writes the whole file and folds the journal into it.
  ASSERT_EQ(
      run_cli("db remove --compact '" + database + "' --vocab '" + vocabulary + "' 1", &output), 0)
      << output;
  ASSERT_EQ(run_cli("info '" + database + "'", &output), 0) << output;
  EXPECT_NE(output.find("entries: 1\nnext_entry_id: 4\n"), std::string::npos) << output;
  EXPECT_NE(output.find("journal: none\n"), std::string::npos) << output;
  EXPECT_EQ(Database::inspect(database, false).entries, 1u);

  // A missing entry changes nothing, even after a valid one.
  const std::vector<std::uint8_t> before = test::read_file(database);
  EXPECT_EQ(run_cli("db remove '" + database + "' --vocab '" + vocabulary + "' 2 3", &output), 1);
  EXPECT_NE(output.find("binbow: error: " + database + ": no entry 3"), std::string::npos)
      << output;
  EXPECT_EQ(test::read_file(database), before);
  EXPECT_EQ(run_cli("db add '" + database + "' --vocab '" + vocabulary + "' '" +
                        dir.file("missing.jpg") + "'",
                    &output),
            1);
  EXPECT_EQ(test::read_file(database), before);
  // Saved through a temporary file and a rename: nothing else is left behind.
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 4u);  // d.bbdb, its writers' d.bbdb.lock, more.txt, 54.jpg
}

TEST(CliDb, ClearErrors) {
  TempDir dir;
  const std::string folder = samples_folder();
  std::string output;
  EXPECT_EQ(run_cli("db query '" + dir.file("missing.bbdb") + "' '" + folder + "/1.jpg'", &output),
            1);
  EXPECT_NE(output.find("binbow: error: " + dir.file("missing.bbdb") + ": cannot open"),
            std::string::npos)
      << output;

  test::write_file(dir.file("bad.bbdb"), std::vector<std::uint8_t>(200, 'B'));
  EXPECT_EQ(run_cli("db query '" + dir.file("bad.bbdb") + "' '" + folder + "/1.jpg'", &output), 1);
  EXPECT_NE(output.find("not a binbow database"), std::string::npos) << output;

  const std::string vocabulary = shared_data("kimera-small-voc/small_voc.yml.gz");
  EXPECT_NE(run_cli("db build --vocab '" + vocabulary + "' -o '" + dir.file("x.bbdb") + "' '" +
                        dir.path() + "'",
                    &output),
            0);
  EXPECT_NE(output.find("error"), std::string::npos) << output;
}

// Real ORB features of the corridor, a real DBoW2 ORB vocabulary, every
// scoring: the database answers exactly what brute force answers.
// A database of the corridor's first frames, for the writer tests.
std::string small_corridor_database(const TempDir& dir) {
  const std::string database = dir.file("writers.bbdb");
  std::string output;
  EXPECT_EQ(
      run_cli("db build --vocab '" + shared_data("kimera-small-voc/small_voc.yml.gz") + "' -o '" +
                  database + "' '" + samples_folder() + "/1.jpg' '" + samples_folder() + "/2.jpg'",
              &output),
      0)
      << output;
  return database;
}

double entries_of(const std::string& database) {
  std::string output;
  EXPECT_EQ(run_cli("info '" + database + "'", &output), 0) << output;
  return test::printed_number(output, "entries");
}

// One writer at a time: a second `db add` started while the first runs
// waits for it (--wait), and no acknowledged add is lost.
TEST(CliDb, ConcurrentAddsWaitForEachOtherAndLoseNothing) {
  TempDir dir;
  const std::string database = small_corridor_database(dir);
  constexpr int kPairs = 8, kImages = 3;
  for (int pair = 0; pair < kPairs; ++pair) {
    std::string command;
    for (int writer = 0; writer < 2; ++writer) {
      command += "'" BINBOW_CLI "' db add --wait 60 '" + database + "'";
      for (int image = 0; image < kImages; ++image)
        command += " '" + samples_folder() + "/" +
                   std::to_string(10 + kImages * (2 * pair + writer) + image) + ".jpg'";
      command += " > '" + dir.file("out" + std::to_string(writer)) + "' 2>&1 & ";
    }
    std::string output;
    ASSERT_EQ(test::run_command(command + "wait", &output), 0) << output;
    for (int writer = 0; writer < 2; ++writer) {
      const std::vector<std::uint8_t> printed =
          test::read_file(dir.file("out" + std::to_string(writer)));
      const std::string text(printed.begin(), printed.end());
      EXPECT_NE(text.find(std::to_string(kImages) + " entries added"), std::string::npos) << text;
    }
  }
  EXPECT_EQ(entries_of(database), 2 + 2 * kPairs * kImages);
}

TEST(CliDb, ASecondWriterIsToldWhoHoldsTheDatabase) {
  TempDir dir;
  const std::string database = small_corridor_database(dir);
  const std::string image = "'" + samples_folder() + "/30.jpg'";
  const DatabaseLock held(database);
  std::string output;
  for (const std::string& wait : {std::string(), std::string(" --wait 0.2")}) {
    EXPECT_EQ(run_cli("db add '" + database + "' " + image + wait, &output), 1) << output;
    EXPECT_EQ(output.find("binbow: error: "), 0u) << output;
    EXPECT_NE(output.find("another writer is changing the database (process " +
                          std::to_string(::getpid())),
              std::string::npos)
        << output;
    EXPECT_NE(output.find(wait.empty() ? "--wait SECONDS waits for it" : "after waiting 0.2 s"),
              std::string::npos)
        << output;
    EXPECT_EQ(run_cli("db remove '" + database + "' 0" + wait, &output), 1) << output;
  }
  EXPECT_EQ(entries_of(database), 2);
}

// info answers what a load would: a journal whose change cannot apply (an
// entry removed twice) makes info fail as db query does.
TEST(CliDb, InfoRefusesADatabaseThatDoesNotLoad) {
  TempDir dir;
  const std::string database = small_corridor_database(dir);
  Database loaded = Database::load(database);
  loaded.remove(1);
  loaded.save_incremental(database);
  std::vector<std::uint8_t> journal = test::read_file(Database::journal_path(database));
  const std::size_t record = 32;  // the first record follows the journal's header
  journal.insert(journal.end(), journal.begin() + record, journal.end());
  test::write_file(Database::journal_path(database), journal);
  std::string output;
  EXPECT_EQ(run_cli("db query '" + database + "' '" + samples_folder() + "/1.jpg'", &output), 1)
      << output;
  EXPECT_EQ(run_cli("info '" + database + "'", &output), 1) << output;
  EXPECT_NE(output.find("binbow: error: "), std::string::npos) << output;
  EXPECT_EQ(output.find("entries:"), std::string::npos) << output;
}

TEST(DatabaseRealData, QueriesEqualBruteForce) {
  const Vocabulary base = load_vocabulary(shared_data("kimera-small-voc/small_voc.yml.gz"));
  vision::ImageSource source({samples_folder()});
  const auto extractor = vision::make_extractor("orb", 500);
  std::vector<DescriptorMatrix> images;
  vision::Frame frame;
  while (source.next(frame)) images.push_back(extractor->extract(frame.image).descriptors);
  ASSERT_EQ(images.size(), 84u);

  for (Scoring scoring : {Scoring::kL1, Scoring::kL2, Scoring::kChiSquare, Scoring::kKL,
                          Scoring::kBhattacharyya, Scoring::kDotProduct}) {
    const Vocabulary vocabulary = base.with_scoring(scoring);
    Database database(vocabulary);
    std::vector<BowVector> bows(images.size());
    for (std::size_t i = 0; i < images.size(); ++i) {
      vocabulary.transform(images[i].view(), bows[i]);
      database.add(bows[i]);
    }
    database.remove(40);
    for (std::size_t q = 0; q < images.size(); q += 3) {
      std::vector<QueryResult> expected;
      for (EntryId e = 0; e < bows.size(); ++e) {
        if (e == 40) continue;
        std::uint32_t shared = 0;
        for (const BowEntry& word : bows[q])
          shared += std::any_of(bows[e].begin(), bows[e].end(),
                                [&](const BowEntry& x) { return x.word == word.word; });
        if (shared > 0) expected.push_back({e, vocabulary.score(bows[q], bows[e]), shared});
      }
      std::stable_sort(expected.begin(), expected.end(), [&](const auto& a, const auto& b) {
        return scoring == Scoring::kKL ? a.score < b.score : a.score > b.score;
      });
      expected.resize(std::min<std::size_t>(expected.size(), 15));
      EXPECT_EQ(database.query(bows[q], 15), expected) << to_string(scoring) << " query " << q;
    }
  }
}

}  // namespace
}  // namespace binbow
