// The DBoW2 layer beyond the golden numbers: erase, files, errors, create(),
// BRIEF descriptors, printing.
#include <gtest/gtest.h>

#include <algorithm>
#include <bitset>
#include <cstdint>
#include <fstream>
#include <initializer_list>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "binbow/compat/DBoW2.h"
#include "binbow/formats.h"
#include "compat/dbow2_golden.h"
#include "support/query_results.h"
#include "support/test_support.h"

namespace {

using binbow::test::source_path;
using binbow::test::TempDir;

const dbow2_golden::Golden& golden() {
  static const dbow2_golden::Golden g =
      dbow2_golden::read(source_path("tests/compat/dbow2_golden.txt"));
  return g;
}

const OrbVocabulary& vocabulary() {
  static const OrbVocabulary voc(source_path("data/vocab/orb_default.bbw"));
  return voc;
}

std::vector<DBoW2::BowVector> bows_of(const OrbVocabulary& voc) {
  std::vector<DBoW2::BowVector> bows(golden().images.size());
  for (std::size_t i = 0; i < bows.size(); ++i) voc.transform(golden().images[i], bows[i]);
  return bows;
}

// Expects `f` to throw std::runtime_error whose message names `path`.
template <class F>
void expect_error_naming(const std::string& path, F f) {
  try {
    f();
    ADD_FAILURE() << "no error for " << path;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(Dbow2Database, EraseRemovesTheEntryFromQueriesAndTheDirectIndex) {
  OrbDatabase db(vocabulary(), true, 1);
  for (const auto& image : golden().images) db.add(image);
  DBoW2::QueryResults before;
  db.query(golden().images[1], before, 0);
  ASSERT_EQ(1u, before[0].Id);

  db.erase(1);
  EXPECT_EQ(golden().images.size(), db.size());  // ids are not reused
  for (std::size_t q = 0; q < golden().images.size(); ++q) {
    DBoW2::QueryResults ret;
    db.query(golden().images[q], ret, 0);
    for (const DBoW2::Result& r : ret) EXPECT_NE(1u, r.Id) << "query " << q;
  }
  DBoW2::QueryResults after;
  db.query(golden().images[1], after, 0);
  EXPECT_EQ(before.size() - 1, after.size());
  EXPECT_THROW(db.retrieveFeatures(1), std::runtime_error);
  EXPECT_THROW(db.erase(1), std::runtime_error);
  EXPECT_THROW(db.erase(100), std::runtime_error);
  EXPECT_EQ(golden().images.size(), db.add(golden().images[1]));  // a new id
  db.query(golden().images[1], after, 1);
  EXPECT_EQ(golden().images.size(), after[0].Id);
}

std::size_t file_size(const std::string& path) {
  std::ifstream file(path.c_str(), std::ios::binary | std::ios::ate);
  return static_cast<std::size_t>(file.tellg());
}

// A saved database holds the index as memory holds it: its size shows that
// erased entries' postings and feature vectors are gone, not just hidden.
TEST(Dbow2Database, EraseFreesTheEntriesMemory) {
  TempDir dir;
  OrbDatabase db(vocabulary(), true, 2);
  db.save(dir.file("empty.bbdb"));  // the vocabulary alone
  const std::size_t entries = 60 * golden().images.size();
  for (std::size_t i = 0; i < entries; ++i) db.add(golden().images[i % golden().images.size()]);
  db.save(dir.file("all.bbdb"));
  for (DBoW2::EntryId id = 0; id < entries * 3 / 4; ++id) db.erase(id);
  db.save(dir.file("quarter.bbdb"));
  const std::size_t empty = file_size(dir.file("empty.bbdb"));
  const std::size_t all = file_size(dir.file("all.bbdb")) - empty;
  const std::size_t quarter = file_size(dir.file("quarter.bbdb")) - empty;
  EXPECT_LT(quarter, all * 2 / 5) << "entries' bytes: " << all << " before, " << quarter
                                  << " after erasing three quarters";
}

TEST(Dbow2Database, AddFillsTheVectorsAndKeepsTheDirectIndex) {
  OrbDatabase db(vocabulary(), true, 2);
  EXPECT_TRUE(db.usingDirectIndex());
  EXPECT_EQ(2, db.getDirectIndexLevels());
  DBoW2::BowVector v;
  DBoW2::FeatureVector fv;
  EXPECT_EQ(0u, db.add(golden().images[0], &v, &fv));
  DBoW2::BowVector expected_v;
  DBoW2::FeatureVector expected_fv;
  vocabulary().transform(golden().images[0], expected_v, expected_fv, 2);
  EXPECT_TRUE(v == expected_v);
  EXPECT_TRUE(fv == expected_fv);
  EXPECT_TRUE(db.retrieveFeatures(0) == expected_fv);
  EXPECT_EQ(1u, db.add(v, fv));
  EXPECT_TRUE(db.retrieveFeatures(1) == expected_fv);
  EXPECT_EQ(vocabulary().size(), db.getVocabulary()->size());

  std::ostringstream out;
  out << db;
  EXPECT_EQ(
      "Database: Entries = 2, Using direct index = yes, Direct index levels = 2. "
      "Vocabulary: k = 10, L = 4, Weighting = tf-idf, Scoring = L1-norm, Number of words = " +
          std::to_string(vocabulary().size()),
      out.str());
  db.allocate(100, 10);
  EXPECT_EQ(2u, db.size());

  db.clear();
  EXPECT_EQ(0u, db.size());
  EXPECT_EQ(0u, db.add(v));

  OrbDatabase without_di(vocabulary(), false);
  DBoW2::FeatureVector level0;
  without_di.add(golden().images[0], NULL, &level0);  // filled although not kept
  vocabulary().transform(golden().images[0], expected_v, expected_fv, 0);
  EXPECT_TRUE(level0 == expected_fv);
  EXPECT_THROW(without_di.retrieveFeatures(0), std::runtime_error);
}

TEST(Dbow2Database, MaxIdAndMaxResultsFollowDbow2) {
  OrbDatabase db(vocabulary(), false);
  for (const auto& image : golden().images) db.add(image);
  DBoW2::QueryResults ret;
  db.query(golden().images[0], ret, 1, 0);
  EXPECT_TRUE(ret.empty());
  db.query(golden().images[0], ret, 1, -2);
  EXPECT_TRUE(ret.empty());
  db.query(golden().images[0], ret, -1, 1);
  ASSERT_EQ(1u, ret.size());
  EXPECT_EQ(0u, ret[0].Id);
  db.query(DBoW2::BowVector(), ret, 3);
  EXPECT_TRUE(ret.empty());
}

TEST(Dbow2Database, WithoutVocabularyAddAndQueryThrow) {
  OrbDatabase db;
  EXPECT_EQ(NULL, db.getVocabulary());
  DBoW2::QueryResults ret;
  EXPECT_THROW(db.add(golden().images[0]), std::logic_error);
  EXPECT_THROW(db.query(golden().images[0], ret), std::logic_error);
  db.setVocabulary(vocabulary());
  EXPECT_EQ(0u, db.add(golden().images[0]));
}

TEST(Dbow2Database, CopiesAreIndependent) {
  OrbDatabase db(vocabulary());
  for (const auto& image : golden().images) db.add(image);
  OrbDatabase copy(db);
  db.erase(0);
  DBoW2::QueryResults ret;
  copy.query(golden().images[0], ret, 1);
  EXPECT_EQ(0u, ret[0].Id);
  copy = db;
  copy.query(golden().images[0], ret, 1);
  EXPECT_NE(0u, ret[0].Id);
}

TEST(Dbow2Database, SaveLoadRoundTrip) {
  TempDir dir;
  OrbVocabulary voc = vocabulary();
  voc.setScoringType(DBoW2::CHI_SQUARE);
  OrbDatabase db(voc, true, 2);
  for (const auto& image : golden().images) db.add(image);
  db.erase(3);
  db.save(dir.file("db.bbdb"));

  OrbDatabase loaded(dir.file("db.bbdb"));
  EXPECT_EQ(db.size(), loaded.size());
  EXPECT_TRUE(loaded.usingDirectIndex());
  EXPECT_EQ(2, loaded.getDirectIndexLevels());
  EXPECT_EQ(DBoW2::CHI_SQUARE, loaded.getVocabulary()->getScoringType());
  EXPECT_EQ(voc.size(), loaded.getVocabulary()->size());
  for (std::size_t q = 0; q < golden().images.size(); ++q) {
    DBoW2::QueryResults a, b;
    db.query(golden().images[q], a, 0);
    loaded.query(golden().images[q], b, 0);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t r = 0; r < a.size(); ++r) {
      EXPECT_EQ(a[r].Id, b[r].Id);
      EXPECT_EQ(a[r].Score, b[r].Score);
    }
  }
  EXPECT_TRUE(loaded.retrieveFeatures(5) == db.retrieveFeatures(5));
  EXPECT_THROW(loaded.retrieveFeatures(3), std::runtime_error);
}

TEST(Dbow2Database, FileErrorsNameTheFile) {
  TempDir dir;
  OrbDatabase db(vocabulary());
  const std::string missing = dir.file("missing.bbdb");
  expect_error_naming(missing, [&] { db.load(missing); });
  expect_error_naming(missing, [&] { OrbDatabase loaded(missing); });
  const std::string damaged = dir.file("damaged.bbdb");
  std::ofstream(damaged.c_str()) << "not a database";
  expect_error_naming(damaged, [&] { db.load(damaged); });
  EXPECT_EQ(vocabulary().size(), db.getVocabulary()->size());  // unchanged by the failures
  const std::string blocked = dir.file("damaged.bbdb/db.bbdb");
  expect_error_naming(blocked, [&] { db.save(blocked); });
}

// binbow's own load checks a database's postings in the background and
// reports damage at a later call; DBoW2 code expects load to fail instead.
TEST(Dbow2Database, LoadFailsOnDamagedPostings) {
  TempDir dir;
  OrbDatabase db(vocabulary(), true, 1);
  for (const auto& image : golden().images) db.add(image);
  const std::string path = dir.file("db.bbdb");
  db.save(path);
  std::vector<std::uint8_t> bytes = binbow::test::read_file(path);
  constexpr std::uint32_t kPostingsSection = 5;
  const auto section = binbow::test::bbdb_section(bytes, kPostingsSection);
  ASSERT_GT(section.second, 16u);
  bytes[section.first + section.second / 2] ^= 0x10;
  binbow::test::write_file(path, bytes);

  OrbDatabase loaded(vocabulary());
  expect_error_naming(path, [&] { loaded.load(path); });
  EXPECT_EQ(0u, loaded.size());  // unchanged by the failure
  expect_error_naming(path, [&] { OrbDatabase constructed(path); });
}

TEST(Dbow2Vocabulary, SaveLoadRoundTripsInEveryFormat) {
  TempDir dir;
  OrbVocabulary voc = vocabulary();
  voc.setScoringType(DBoW2::L2_NORM);
  const std::vector<DBoW2::BowVector> expected = bows_of(voc);
  for (const char* name : {"voc.yml.gz", "voc.yml", "voc.txt", "voc.bin", "voc.bbw", "voc.dbow3"}) {
    voc.save(dir.file(name));
    const OrbVocabulary loaded(dir.file(name));
    EXPECT_EQ(voc.size(), loaded.size()) << name;
    EXPECT_EQ(voc.getBranchingFactor(), loaded.getBranchingFactor()) << name;
    EXPECT_EQ(voc.getDepthLevels(), loaded.getDepthLevels()) << name;
    EXPECT_EQ(DBoW2::L2_NORM, loaded.getScoringType()) << name;
    EXPECT_TRUE(expected == bows_of(loaded)) << name;
  }
  OrbVocabulary text;
  voc.saveToTextFile(dir.file("orbvoc.txt"));
  ASSERT_TRUE(text.loadFromTextFile(dir.file("orbvoc.txt")));
  EXPECT_TRUE(expected == bows_of(text));
  EXPECT_EQ(binbow::VocabularyFormat::kOrbSlamText,
            binbow::detect_vocabulary_format(dir.file("orbvoc.txt")));
  OrbVocabulary binary;
  voc.saveToBinaryFile(dir.file("orbvoc.bin"));
  ASSERT_TRUE(binary.loadFromBinaryFile(dir.file("orbvoc.bin")));
  EXPECT_TRUE(expected == bows_of(binary));
  OrbVocabulary through_load_bin;
  through_load_bin.loadBin(dir.file("voc.yml.gz"));  // detection, whatever the format
  EXPECT_TRUE(expected == bows_of(through_load_bin));
}

// VINS-Mono and VINS-Fusion load their brief_k10L6.bin with loadBin.
TEST(Dbow2Vocabulary, LoadBinReadsVinsBinaryVocabularies) {
  TempDir dir;
  const std::string bbw = source_path("data/vocab/brief_default.bbw");
  const binbow::Vocabulary core = binbow::load_vocabulary(bbw);
  binbow::save_vocabulary(core, dir.file("brief_k10L6.bin"), binbow::VocabularyFormat::kVinsBinary);
  ASSERT_EQ(binbow::VocabularyFormat::kVinsBinary,
            binbow::detect_vocabulary_format(dir.file("brief_k10L6.bin")));
  BriefVocabulary vins;
  vins.loadBin(dir.file("brief_k10L6.bin"));
  const BriefVocabulary original(bbw);
  ASSERT_EQ(original.size(), vins.size());
  EXPECT_EQ(original.getBranchingFactor(), vins.getBranchingFactor());
  EXPECT_EQ(original.getDepthLevels(), vins.getDepthLevels());
  std::mt19937_64 rng(11);
  for (int i = 0; i < 100; ++i) {
    const binbow::DescriptorMatrix bytes = binbow::test::random_descriptors(1, 32, rng);
    const cv::Mat row(1, 32, CV_8U, const_cast<std::uint8_t*>(bytes.row(0)));
    EXPECT_EQ(original.transform(row), vins.transform(row));
  }
  for (DBoW2::WordId w = 0; w < original.size(); w += 97)
    EXPECT_FLOAT_EQ(original.getWordWeight(w), vins.getWordWeight(w)) << w;
}

TEST(Dbow2Vocabulary, StopWordsAndWeightingSurviveSave) {
  TempDir dir;
  OrbVocabulary voc = vocabulary();
  const int stopped = voc.stopWords(2.0);
  EXPECT_GT(stopped, 0);
  voc.setWeightingType(DBoW2::BINARY);
  voc.save(dir.file("voc.yml.gz"));
  const OrbVocabulary loaded(dir.file("voc.yml.gz"));
  EXPECT_EQ(DBoW2::BINARY, loaded.getWeightingType());
  int zero = 0;
  for (DBoW2::WordId w = 0; w < loaded.size(); ++w) zero += loaded.getWordWeight(w) == 0;
  EXPECT_EQ(stopped, zero);
  EXPECT_TRUE(bows_of(voc) == bows_of(loaded));
}

TEST(Dbow2Vocabulary, FileErrorsNameTheFile) {
  TempDir dir;
  OrbVocabulary voc;
  const std::string missing = dir.file("missing.yml.gz");
  expect_error_naming(missing, [&] { voc.load(missing); });
  expect_error_naming(missing, [&] { OrbVocabulary loaded(missing); });
  expect_error_naming(missing, [&] { OrbVocabulary loaded(missing.c_str()); });
  expect_error_naming(missing, [&] { voc.loadBin(missing); });
  const std::string damaged = dir.file("damaged.txt");
  std::ofstream(damaged.c_str()) << "10 6 0 0\n0 1 2 3 4\n0 0 1\n";
  expect_error_naming(damaged, [&] { voc.load(damaged); });
  EXPECT_FALSE(voc.loadFromTextFile(damaged));
  EXPECT_FALSE(voc.loadFromTextFile(missing));
  EXPECT_FALSE(voc.loadFromBinaryFile(missing));
  EXPECT_TRUE(voc.empty());
  expect_error_naming(dir.file("empty.yml"), [&] { voc.save(dir.file("empty.yml")); });
  const OrbVocabulary& loaded = vocabulary();
  expect_error_naming(dir.file("voc.unknown"), [&] { loaded.save(dir.file("voc.unknown")); });
}

TEST(Dbow2Vocabulary, EmptyVocabularyTransformsToEmptyVectors) {
  OrbVocabulary voc(9, 3);
  EXPECT_TRUE(voc.empty());
  EXPECT_EQ(0u, voc.size());
  EXPECT_EQ(9, voc.getBranchingFactor());
  EXPECT_EQ(3, voc.getDepthLevels());
  DBoW2::BowVector v;
  v.addWeight(1, 1);
  DBoW2::FeatureVector fv;
  fv.addFeature(1, 1);
  voc.transform(golden().images[0], v, fv, 0);
  EXPECT_TRUE(v.empty());
  EXPECT_TRUE(fv.empty());
  EXPECT_EQ(0u, voc.transform(golden().images[0][0]));
}

TEST(Dbow2Vocabulary, CreateBuildsAUsableVocabulary) {
  std::vector<std::vector<cv::Mat> > training(golden().images.begin(), golden().images.end() - 1);
  OrbVocabulary voc(5, 3, DBoW2::TF_IDF, DBoW2::L1_NORM);
  voc.create(training);
  EXPECT_EQ(5, voc.getBranchingFactor());
  EXPECT_EQ(3, voc.getDepthLevels());
  EXPECT_GT(voc.size(), 25u);
  EXPECT_LE(voc.size(), 125u);
  DBoW2::BowVector a, b;
  voc.transform(training[1], a);
  voc.transform(training[3], b);
  EXPECT_NEAR(1.0, voc.score(a, a), 1e-12);
  EXPECT_LT(voc.score(a, b), 1.0);
  voc.create(training, 4, 2, DBoW2::TF, DBoW2::DOT_PRODUCT);
  EXPECT_EQ(4, voc.getBranchingFactor());
  EXPECT_EQ(DBoW2::TF, voc.getWeightingType());
  EXPECT_EQ(DBoW2::DOT_PRODUCT, voc.getScoringType());
  EXPECT_LE(voc.size(), 16u);
  EXPECT_THROW(voc.create(training, 1, 2), std::invalid_argument);
  EXPECT_THROW(voc.create(std::vector<std::vector<cv::Mat> >()), std::invalid_argument);
}

TEST(Dbow2Vocabulary, WordsNodesAndDescriptors) {
  const OrbVocabulary& voc = vocabulary();
  const DBoW2::WordId word = golden().feature_words[0][0];
  const cv::Mat centre = voc.getWord(word);
  EXPECT_EQ(32, centre.cols);
  EXPECT_LE(DBoW2::FORB::distance(centre, golden().images[0][0]), 128.0);
  std::vector<DBoW2::WordId> words;
  voc.getWordsFromNode(voc.getParentNode(word, 1), words);
  EXPECT_NE(std::find(words.begin(), words.end(), word), words.end());
  voc.getWordsFromNode(0, words);
  EXPECT_EQ(voc.size(), words.size());
  voc.getWordsFromNode(voc.getParentNode(word, 0), words);
  EXPECT_EQ(std::vector<DBoW2::WordId>(1, word), words);
  EXPECT_GT(voc.getEffectiveLevels(), 3.9f);
  EXPECT_LE(voc.getEffectiveLevels(), 4.0f);
  EXPECT_THROW(voc.getWordWeight(voc.size()), std::out_of_range);
  EXPECT_THROW(voc.getParentNode(voc.size(), 1), std::out_of_range);
  EXPECT_THROW(voc.transform(cv::Mat::zeros(1, 16, CV_8U)), std::invalid_argument);
  DBoW2::BowVector v;
  DBoW2::FeatureVector fv;
  EXPECT_THROW(voc.transform(golden().images[0], v, fv, -1), std::invalid_argument);
}

// Word and node ids outside the vocabulary are std::out_of_range wherever
// they are given, the database's add and query included.
TEST(Dbow2Database, IdsOutsideTheVocabularyAreOutOfRange) {
  OrbDatabase db(vocabulary(), true, 1);
  DBoW2::BowVector outside;
  outside.addWeight(0, 0.5);
  outside.addWeight(vocabulary().size(), 0.5);
  DBoW2::BowVector inside;
  inside.addWeight(0, 1.0);
  DBoW2::FeatureVector far_node;
  far_node.addFeature(100000000, 0);
  EXPECT_THROW(db.add(outside), std::out_of_range);
  EXPECT_THROW(db.add(inside, far_node), std::out_of_range);
  DBoW2::QueryResults ret;
  EXPECT_THROW(db.query(outside, ret), std::out_of_range);
  EXPECT_EQ(0u, db.size());  // nothing added
  EXPECT_EQ(0u, db.add(inside));
  db.query(inside, ret);
  ASSERT_EQ(1u, ret.size());
  try {
    db.add(outside);
    ADD_FAILURE() << "no error";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("word " + std::to_string(vocabulary().size())),
              std::string::npos)
        << e.what();
  }
}

// A BRIEF descriptor with exactly the tests in `tests` set.
DBoW2::FBrief::TDescriptor brief_with_tests(std::initializer_list<int> tests) {
  DBoW2::FBrief::TDescriptor d;
  for (int test : tests) d.set(static_cast<std::size_t>(test));
  return d;
}

TEST(Dbow2Vocabulary, BriefDescriptorsAreBitsetsOrMatRowsInDbow2BitOrder) {
  const BriefVocabulary voc(source_path("data/vocab/brief_default.bbw"));
  const binbow::Vocabulary core =
      binbow::load_vocabulary(source_path("data/vocab/brief_default.bbw"));
  std::mt19937_64 rng(5);
  for (int i = 0; i < 200; ++i) {
    const binbow::DescriptorMatrix bytes = binbow::test::random_descriptors(1, 32, rng);
    const cv::Mat row(1, 32, CV_8U, const_cast<std::uint8_t*>(bytes.row(0)));
    EXPECT_EQ(core.quantize(bytes.row(0)), voc.transform(row));
    DBoW2::FBrief::TDescriptor bits;
    for (std::size_t b = 0; b < bits.size(); ++b) bits[b] = (bytes.row(0)[b / 8] >> (b % 8)) & 1;
    EXPECT_EQ(core.quantize(bytes.row(0)), voc.transform(bits));
  }
  // getWord gives the word's bits in the same order (here against the bytes
  // of the same file's words as rows).
  const OrbVocabulary rows(source_path("data/vocab/brief_default.bbw"));
  const DBoW2::FBrief::TDescriptor word = voc.getWord(7);
  const cv::Mat row = rows.getWord(7);
  for (std::size_t b = 0; b < word.size(); ++b)
    EXPECT_EQ(((row.at<unsigned char>(0, static_cast<int>(b / 8)) >> (b % 8)) & 1) != 0, word[b])
        << b;
  TempDir dir;
  voc.save(dir.file("brief.yml"));  // FBrief's bit strings, as DBoW2 writes them
  std::ifstream file(dir.file("brief.yml").c_str());
  std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("descriptor:\"" + DBoW2::FBrief::toString(voc.getWord(5)) + "\""),
            std::string::npos);
  // And the file reads back as the same words.
  const BriefVocabulary reread(dir.file("brief.yml"));
  for (DBoW2::WordId w = 0; w < 20; ++w)
    EXPECT_EQ(0, DBoW2::FBrief::distance(voc.getWord(w), reread.getWord(w))) << w;
}

TEST(Dbow2Descriptors, ForbAndFbriefFunctions) {
  const cv::Mat& a = golden().images[0][0];
  const cv::Mat& b = golden().images[0][1];
  int bits = 0;
  for (int i = 0; i < 32; ++i)
    bits += static_cast<int>(
        std::bitset<8>(a.at<unsigned char>(0, i) ^ b.at<unsigned char>(0, i)).count());
  EXPECT_EQ(bits, DBoW2::FORB::distance(a, b));
  cv::Mat parsed;
  DBoW2::FORB::fromString(parsed, DBoW2::FORB::toString(a));
  EXPECT_EQ(0, DBoW2::FORB::distance(a, parsed));
  std::vector<DBoW2::FORB::pDescriptor> three = {&a, &a, &b};
  cv::Mat mean;
  DBoW2::FORB::meanValue(three, mean);
  EXPECT_EQ(0, DBoW2::FORB::distance(a, mean));
  cv::Mat floats;
  DBoW2::FORB::toMat32F(std::vector<cv::Mat>(1, a), floats);
  EXPECT_EQ(256, floats.cols);
  EXPECT_EQ((a.at<unsigned char>(0, 0) >> 7) & 1, floats.at<float>(0, 0));
  cv::Mat rows;
  DBoW2::FORB::toMat8U(golden().images[0], rows);
  EXPECT_EQ(static_cast<int>(golden().images[0].size()), rows.rows);

  const DBoW2::FBrief::TDescriptor x = brief_with_tests({3, 200});
  const DBoW2::FBrief::TDescriptor y = brief_with_tests({3});
  EXPECT_EQ(1, DBoW2::FBrief::distance(x, y));
  // DBoW2's bitset::to_string: test 255 first.
  const std::string text = DBoW2::FBrief::toString(x);
  ASSERT_EQ(256u, text.size());
  EXPECT_EQ('1', text[255 - 3]);
  EXPECT_EQ('1', text[255 - 200]);
  EXPECT_EQ(2, std::count(text.begin(), text.end(), '1'));
  EXPECT_EQ(x.to_string(), text);
  DBoW2::FBrief::TDescriptor z;
  DBoW2::FBrief::fromString(z, text);
  EXPECT_EQ(x, z);
  EXPECT_THROW(DBoW2::FBrief::fromString(z, "0101"), std::invalid_argument);
  // DBoW2's majority: more than half.
  std::vector<DBoW2::FBrief::pDescriptor> votes = {&x, &x, &y};
  DBoW2::FBrief::meanValue(votes, z);
  EXPECT_EQ(x, z);
  votes = {&x, &y};
  DBoW2::FBrief::meanValue(votes, z);
  EXPECT_EQ(y, z);
  DBoW2::FBrief::meanValue(std::vector<DBoW2::FBrief::pDescriptor>(), z);
  EXPECT_TRUE(z.none());
  cv::Mat brief_floats;
  DBoW2::FBrief::toMat32F(std::vector<DBoW2::FBrief::TDescriptor>(1, x), brief_floats);
  ASSERT_EQ(256, brief_floats.cols);
  EXPECT_EQ(1.f, brief_floats.at<float>(0, 3));
  EXPECT_EQ(0.f, brief_floats.at<float>(0, 4));
  EXPECT_EQ(1.f, brief_floats.at<float>(0, 200));
}

// A type outside DBoW2's enums is refused where it is set: kept, it would
// index past the names operator<< prints and reach transform() and score().
TEST(Dbow2Vocabulary, WeightingAndScoringOutsideTheirEnumsAreRefused) {
  OrbVocabulary voc = vocabulary();
  EXPECT_THROW(voc.setWeightingType(static_cast<DBoW2::WeightingType>(4)), std::invalid_argument);
  EXPECT_THROW(voc.setWeightingType(static_cast<DBoW2::WeightingType>(-1)), std::invalid_argument);
  EXPECT_THROW(voc.setScoringType(static_cast<DBoW2::ScoringType>(6)), std::invalid_argument);
  EXPECT_THROW(voc.setScoringType(static_cast<DBoW2::ScoringType>(1000)), std::invalid_argument);
  ASSERT_EQ(DBoW2::TF_IDF, voc.getWeightingType());  // unchanged
  ASSERT_EQ(DBoW2::L1_NORM, voc.getScoringType());
  std::ostringstream out;
  out << voc;
  EXPECT_NE(out.str().find("Weighting = tf-idf, Scoring = L1-norm"), std::string::npos)
      << out.str();
  EXPECT_THROW(OrbVocabulary(10, 5, static_cast<DBoW2::WeightingType>(9)), std::invalid_argument);
  EXPECT_THROW(OrbVocabulary(10, 5, DBoW2::TF, static_cast<DBoW2::ScoringType>(7)),
               std::invalid_argument);
  const std::vector<std::vector<cv::Mat> > training(2, golden().images[0]);
  OrbVocabulary built;
  EXPECT_THROW(built.create(training, 3, 2, static_cast<DBoW2::WeightingType>(5), DBoW2::L1_NORM),
               std::invalid_argument);
  EXPECT_TRUE(built.empty());
}

TEST(Dbow2Vectors, PrintingAndNormalisationAsDbow2) {
  DBoW2::BowVector v;
  v.addWeight(3, 1.0);
  v.addWeight(1, 2.0);
  v.addWeight(3, 1.0);
  v.addIfNotExist(1, 5.0);
  std::ostringstream out;
  out << v;
  EXPECT_EQ("<1, 2>, <3, 2>", out.str());
  v.normalize(DBoW2::L1);
  EXPECT_DOUBLE_EQ(0.5, v[1]);
  v.normalize(DBoW2::L2);
  EXPECT_DOUBLE_EQ(std::sqrt(0.5), v[3]);

  DBoW2::FeatureVector fv;
  fv.addFeature(7, 2);
  fv.addFeature(4, 0);
  fv.addFeature(7, 5);
  out.str("");
  out << fv;
  EXPECT_EQ("<4: [0]>, <7: [2, 5]>", out.str());

  DBoW2::QueryResults ret;
  ret.push_back(DBoW2::Result(4, 0.5));
  out.str("");
  out << ret;
  EXPECT_EQ("1 result:\n<EntryId: 4, Score: 0.5>", out.str());
  ret.scaleScores(2);
  EXPECT_EQ(1.0, ret[0].Score);

  out.str("");
  out << vocabulary();
  EXPECT_EQ("Vocabulary: k = 10, L = 4, Weighting = tf-idf, Scoring = L1-norm, Number of words = " +
                std::to_string(vocabulary().size()),
            out.str());

  TempDir dir;
  v.saveM(dir.file("v.txt"), 5);
  std::ifstream file(dir.file("v.txt").c_str());
  std::string dense;
  std::getline(file, dense);
  EXPECT_EQ(0u, dense.find("0 0.7"));
  expect_error_naming(dir.file("no/such/dir/v.txt"),
                      [&] { v.saveM(dir.file("no/such/dir/v.txt"), 5); });
}

}  // namespace
