#include "binbow/loop/evaluation.h"

#include <sys/stat.h>

#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include <zlib.h>
#include <opencv2/imgcodecs.hpp>

#include "binbow/error.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

using test::shared_data;
using test::TempDir;

std::set<std::pair<std::size_t, std::size_t>> loops_of(const GroundTruth& truth) {
  std::set<std::pair<std::size_t, std::size_t>> loops;
  for (std::size_t q = 0; q < truth.frames(); ++q)
    for (std::uint32_t m : truth.earlier_matches(q)) loops.emplace(q, m);
  return loops;
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

TEST(GroundTruth, ImageMatrixAgreesWithOneBasedPairs) {
  const GroundTruth image = GroundTruth::load(shared_data("rtabmap-samples/samples_GT.bmp"));
  const GroundTruth pairs = GroundTruth::load(shared_data("rtabmap-samples/samples_GT_pairs.txt"));
  EXPECT_EQ(image.frames(), 84u);
  EXPECT_EQ(pairs.frames(), 84u);
  EXPECT_EQ(loops_of(image), loops_of(pairs));
  EXPECT_EQ(image.queries_with_loops(), 44u);  // frames 41-84 revisit (1-based)
  EXPECT_TRUE(image.is_loop(40, 0));           // "41 1" in the 1-based pair file
  EXPECT_TRUE(image.is_loop(0, 40));           // same place is symmetric
  EXPECT_FALSE(image.has_loop(39));
  EXPECT_TRUE(image.has_loop(40));
}

// The .mat files hold dense double, dense logical matrices; their pair lists are 0-based.
class MatGroundTruth : public testing::TestWithParam<const char*> {};

TEST_P(MatGroundTruth, AgreesWithZeroBasedPairs) {
  const std::string stem = GetParam();
  const GroundTruth mat =
      GroundTruth::load(shared_data("lcd-groundtruth-knzhang/" + stem + ".mat"));
  const GroundTruth pairs =
      GroundTruth::load(shared_data("lcd-groundtruth-knzhang/pairs_txt/" + stem + "_pairs.txt"));
  EXPECT_GT(mat.pair_count(), 100u);
  EXPECT_EQ(loops_of(mat), loops_of(pairs));
  EXPECT_GE(mat.frames(), pairs.frames());
}

INSTANTIATE_TEST_SUITE_P(Knzhang, MatGroundTruth,
                         testing::Values("Lip6IndoorGroundTruth", "city_GT_final",
                                         "kitti06GroundTruth"));

TEST(GroundTruth, TextPairsNeedAKnownBase) {
  TempDir dir;
  write_text(dir.file("a.txt"), "5 2\n6 3\n");
  EXPECT_THROW(GroundTruth::load(dir.file("a.txt")), FileError);
  GroundTruthOptions one_based;
  one_based.pairs_index_base = 1;
  const GroundTruth t = GroundTruth::load(dir.file("a.txt"), one_based);
  EXPECT_TRUE(t.is_loop(4, 1));
  write_text(dir.file("b.txt"), "# comment\n5,0\n\n6\t3\n");
  const GroundTruth z = GroundTruth::load(dir.file("b.txt"));
  EXPECT_TRUE(z.is_loop(5, 0));
  EXPECT_TRUE(z.is_loop(6, 3));
  EXPECT_EQ(z.frames(), 7u);
}

TEST(GroundTruth, DamagedFilesAreFileErrors) {
  TempDir dir;
  write_text(dir.file("bad.txt"), "# 0-based\n1 0\n2 x\n");
  try {
    GroundTruth::load(dir.file("bad.txt"));
    FAIL() << "no error";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  write_text(dir.file("neg.txt"), "# 1-based\n1 0\n");
  EXPECT_THROW(GroundTruth::load(dir.file("neg.txt")), FileError);
  // A truncated .mat: every prefix must fail cleanly or read a subset, never crash.
  const auto bytes =
      test::read_file(shared_data("lcd-groundtruth-knzhang/Lip6IndoorGroundTruth.mat"));
  ASSERT_GT(bytes.size(), 200u);
  for (std::size_t size : {std::size_t{0}, std::size_t{10}, std::size_t{128}, std::size_t{200},
                           bytes.size() / 2, bytes.size() - 1}) {
    test::write_file(dir.file("t.mat"), {bytes.begin(), bytes.begin() + static_cast<long>(size)});
    EXPECT_THROW(GroundTruth::load(dir.file("t.mat")), FileError) << size;
  }
  write_text(dir.file("x.png"), "not an image");
  EXPECT_THROW(GroundTruth::load(dir.file("x.png")), FileError);
  EXPECT_THROW(GroundTruth::load(dir.file("missing.txt")), FileError);
}

void expect_mat_error_mentioning(const std::string& path, const std::string& needle) {
  try {
    GroundTruth::load(path);
    ADD_FAILURE() << "loaded " << path;
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

// matio sizes allocations from a variable's head (found by fuzzing: a
// dimension list declaring 1 GB made it allocate 2 GB) and leaked on
// elements that are not variables; both are refused before matio reads.
TEST(GroundTruth, MatHeadsAreCheckedBeforeMatioAllocates) {
  TempDir dir;
  const auto plain = test::read_file(test::source_path("fuzz/corpus/gt_mat/dense_double.mat"));
  ASSERT_GT(plain.size(), 0xa0u);
  auto huge_dimensions = plain;
  huge_dimensions[0x9f] = 0x3f;  // the high byte of the dimension list's length
  test::write_file(dir.file("dims.mat"), huge_dimensions);
  expect_mat_error_mentioning(dir.file("dims.mat"), "bytes of dimensions");

  auto junk = test::read_file(test::source_path("fuzz/corpus/gt_mat/dense_double_zlib.mat"));
  junk.insert(junk.end(), 16, 0xff);
  test::write_file(dir.file("junk.mat"), junk);
  expect_mat_error_mentioning(dir.file("junk.mat"), "not a variable");

  // Found by fuzzing: a 192-byte matrix declaring 16,777,222 x 4,218,880
  // cells, which the dense reader visited for minutes.
  auto many_cells = plain;
  many_cells[0xa3] = 0x01;  // the first dimension becomes 2^24 + its value
  test::write_file(dir.file("cells.mat"), many_cells);
  expect_mat_error_mentioning(dir.file("cells.mat"), "more cells than");

  // Found by fuzzing: a cell array declaring 4 x 4,294,901,766 cells made
  // matio allocate 128 GB. Nested variables are refused altogether.
  auto cells = plain;
  cells[0x90] = 0x01;                                    // the class: a cell array
  cells[0xa4] = 0x06, cells[0xa6] = cells[0xa7] = 0xff;  // the second dimension
  test::write_file(dir.file("cell.mat"), cells);
  expect_mat_error_mentioning(dir.file("cell.mat"), "a cell array");

  // Found by fuzzing: the text "MATLAB 7.3" on a level-5 file skipped every
  // check, and matio leaked on its damaged compressed variable.
  auto text_says_hdf5 =
      test::read_file(test::source_path("fuzz/corpus/gt_mat/dense_double_zlib.mat"));
  std::copy_n("MATLAB 7.3", 10, text_says_hdf5.begin());
  text_says_hdf5.resize(text_says_hdf5.size() - 8);
  test::write_file(dir.file("hdf5_text.mat"), text_says_hdf5);
  expect_mat_error_mentioning(dir.file("hdf5_text.mat"), "truncated");

  // Found by fuzzing: matio reads a header version other than level 5's or
  // 7.3's as a level-4 file from byte 0, and allocated the 744 MB name its
  // first 20 bytes declared.
  auto version = plain;
  const unsigned char level4_head[20] = {0, 0, 0, 0, 1, 0, 0,    0,    1,    0,
                                         0, 0, 0, 0, 0, 0, 0x69, 0x9c, 0x65, 0x2c};
  std::copy(std::begin(level4_head), std::end(level4_head), version.begin());
  version[124] = 0x09;  // 0x0109, stored as the endian indicator says
  test::write_file(dir.file("version.mat"), version);
  expect_mat_error_mentioning(dir.file("version.mat"), "unsupported .mat header version 0x0109");

  auto damaged = test::read_file(test::source_path("fuzz/corpus/gt_mat/dense_double_zlib.mat"));
  damaged[damaged.size() - 6] ^= 0xff;  // inside the deflate stream or its checksum
  test::write_file(dir.file("damaged.mat"), damaged);
  expect_mat_error_mentioning(dir.file("damaged.mat"), "zlib stream");
}

// A compressed variable holding `matrix` (a miMATRIX element, tag included).
std::vector<unsigned char> compressed_variable(const std::vector<unsigned char>& matrix) {
  uLongf size = compressBound(static_cast<uLong>(matrix.size()));
  std::vector<unsigned char> element(8 + size);
  EXPECT_EQ(compress2(element.data() + 8, &size, matrix.data(), static_cast<uLong>(matrix.size()),
                      Z_BEST_COMPRESSION),
            Z_OK);
  element.resize(8 + size);
  element[0] = 15;  // miCOMPRESSED
  for (int i = 0; i < 4; ++i) element[4 + i] = static_cast<unsigned char>(size >> (8 * i));
  return element;
}

// matio allocates a sparse matrix's arrays from the sizes in their own tags
// and reads a missing one from whatever follows. Found by fuzzing: a 232-byte
// file whose sparse matrix ended after its row indices made matio allocate
// 4 GiB for the column starts it read beyond the matrix.
TEST(GroundTruth, SparseMatrixElementsAreCheckedBeforeMatioAllocates) {
  TempDir dir;
  test::write_file(
      dir.file("found.mat"),
      test::read_file(test::source_path("fuzz/corpus/gt_mat/sparse_missing_column_starts")));
  expect_mat_error_mentioning(dir.file("found.mat"), "1 of the 3 elements it needs");

  // sparse.mat: header (128 bytes), then one miMATRIX whose row indices'
  // tag stands at 0xb0 and whose column starts begin at 0xc8.
  const auto sparse = test::read_file(test::source_path("fuzz/corpus/gt_mat/sparse.mat"));
  ASSERT_EQ(sparse.size(), 0x118u);
  auto long_rows = sparse;
  long_rows[0xb7] = 0x7f;  // the row indices declare 2 GiB
  test::write_file(dir.file("rows.mat"), long_rows);
  expect_mat_error_mentioning(dir.file("rows.mat"), "more than its matrix holds");

  // Found next by fuzzing: column starts typed as bytes, so matio read the
  // values' tag from inside them and allocated 1.7 GB.
  auto byte_columns = sparse;
  byte_columns[0xc8] = 1;  // miINT8
  test::write_file(dir.file("bytes.mat"), byte_columns);
  expect_mat_error_mentioning(dir.file("bytes.mat"), "column starts have type 1");
  auto odd_values = sparse;
  odd_values[0xf4] = 0x1f;  // 31 bytes of doubles
  test::write_file(dir.file("odd.mat"), odd_values);
  expect_mat_error_mentioning(dir.file("odd.mat"), "values have type 9 and 31 bytes");

  // The same matrix cut after its row indices, plain and compressed.
  std::vector<unsigned char> cut(sparse.begin(), sparse.begin() + 0xc8);
  cut[0x84] = 0xc8 - 0x88;  // the matrix's byte count
  test::write_file(dir.file("cut.mat"), cut);
  expect_mat_error_mentioning(dir.file("cut.mat"), "1 of the 3 elements it needs");
  auto cut_zlib = std::vector<unsigned char>(sparse.begin(), sparse.begin() + 128);
  const auto element = compressed_variable({cut.begin() + 128, cut.end()});
  cut_zlib.insert(cut_zlib.end(), element.begin(), element.end());
  test::write_file(dir.file("cut_zlib.mat"), cut_zlib);
  expect_mat_error_mentioning(dir.file("cut_zlib.mat"), "1 of the 3 elements it needs");

  // Recompressed whole, the matrix still loads: the check is not the refusal.
  auto whole_zlib = std::vector<unsigned char>(sparse.begin(), sparse.begin() + 128);
  const auto whole = compressed_variable({sparse.begin() + 128, sparse.end()});
  whole_zlib.insert(whole_zlib.end(), whole.begin(), whole.end());
  test::write_file(dir.file("whole_zlib.mat"), whole_zlib);
  const auto recompressed = GroundTruth::load(dir.file("whole_zlib.mat"));
  const auto plain = GroundTruth::load(test::source_path("fuzz/corpus/gt_mat/sparse.mat"));
  EXPECT_EQ(recompressed.frames(), plain.frames());
  EXPECT_EQ(recompressed.loop_queries(), plain.loop_queries());
  EXPECT_EQ(recompressed.pair_count(), plain.pair_count());
}

TEST(Detections, CsvRoundTripWithAwkwardNames) {
  TempDir dir;
  const std::vector<Detection> detections = {
      {41, 2, "a/41.jpg", "a/2.jpg", 0.53125, 37},
      {42, 3, "odd, \"name\".jpg", "x\ny.jpg", 1e-7, 12},
  };
  write_detections_csv(dir.file("loops.csv"), detections);
  std::ifstream in(dir.file("loops.csv"));
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "query_index,match_index,query_file,match_file,score,inliers");
  const auto read = read_detections_csv(dir.file("loops.csv"));
  ASSERT_EQ(read.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(read[i].query, detections[i].query);
    EXPECT_EQ(read[i].match, detections[i].match);
    EXPECT_EQ(read[i].query_file, detections[i].query_file);
    EXPECT_EQ(read[i].match_file, detections[i].match_file);
    EXPECT_DOUBLE_EQ(read[i].score, detections[i].score);
    EXPECT_EQ(read[i].inliers, detections[i].inliers);
  }
}

TEST(Detections, MalformedCsvNamesTheLine) {
  TempDir dir;
  write_text(dir.file("a.csv"), "first,second\n1,0\n");
  EXPECT_THROW(read_detections_csv(dir.file("a.csv")), FileError);
  write_text(dir.file("b.csv"),
             "query_index,match_index,query_file,match_file,score,inliers\n1,0,a,b,0.5,12\n"
             "2,-1,a,b,0.5,12\n");
  try {
    read_detections_csv(dir.file("b.csv"));
    FAIL() << "no error";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
}

TEST(PrecisionRecall, PaperDefinitions) {
  // 10 frames; queries 5..8 revisit 0..3; query 9 has no loop.
  const GroundTruth truth(10, {{5, 0}, {6, 1}, {7, 2}, {8, 3}, {8, 2}});
  std::vector<Detection> detections = {
      {5, 0, "", "", 1, 20}, {6, 1, "", "", 1, 20}, {7, 1, "", "", 1, 20}, {9, 4, "", "", 1, 20}};
  const PrecisionRecall r = evaluate_detections(detections, truth);
  EXPECT_EQ(r.detections, 4u);
  EXPECT_EQ(r.true_positives, 2u);
  EXPECT_EQ(r.false_positives, 2u);
  EXPECT_EQ(r.queries_with_loops, 4u);
  EXPECT_DOUBLE_EQ(r.precision, 0.5);
  EXPECT_DOUBLE_EQ(r.recall, 0.5);

  const PrecisionRecall none = evaluate_detections({}, truth);
  EXPECT_DOUBLE_EQ(none.precision, 1);
  EXPECT_DOUBLE_EQ(none.recall, 0);
  EXPECT_THROW(evaluate_detections({{10, 0, "", "", 1, 1}}, truth), InvalidArgument);
}

TEST(PrecisionRecall, CurveByScoreAndRecallAtFullPrecision) {
  const GroundTruth truth(10, {{5, 0}, {6, 1}, {7, 2}, {8, 3}});
  const std::vector<Detection> detections = {{5, 0, "", "", 0.9, 0},
                                             {6, 1, "", "", 0.8, 0},
                                             {9, 2, "", "", 0.5, 0},
                                             {7, 2, "", "", 0.4, 0}};
  const auto curve = pr_curve_by_score(detections, truth);
  ASSERT_EQ(curve.size(), 4u);
  EXPECT_DOUBLE_EQ(curve[0].parameter, 0.4);
  EXPECT_DOUBLE_EQ(curve[0].result.recall, 0.75);
  EXPECT_DOUBLE_EQ(curve[0].result.precision, 0.75);
  EXPECT_DOUBLE_EQ(recall_at_full_precision(curve), 0.5);  // thresholds 0.8 and above
  EXPECT_DOUBLE_EQ(recall_at_full_precision({}), 0);
}

// The curve by score, computed in one pass, equals evaluating the detections
// kept at every threshold one by one.
TEST(PrecisionRecall, CurveByScoreEqualsEvaluatingEveryThreshold) {
  std::mt19937_64 rng(7);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t q = 20; q < 200; ++q)
    if (rng() % 3 == 0) pairs.emplace_back(q, q - 10 - rng() % 10);
  const GroundTruth truth(200, pairs);
  std::vector<Detection> detections;
  for (int i = 0; i < 300; ++i) {
    const std::size_t query = 20 + rng() % 180;
    const std::size_t match = rng() % 2 == 0 ? query - 10 - rng() % 10 : rng() % 200;
    detections.push_back({query, match, "", "", static_cast<double>(rng() % 40) / 8, 0});
  }
  const std::vector<PrCurvePoint> curve = pr_curve_by_score(detections, truth);
  std::set<double> scores;
  for (const Detection& d : detections) scores.insert(d.score);
  ASSERT_EQ(curve.size(), scores.size());
  std::size_t i = 0;
  for (double t : scores) {
    std::vector<Detection> kept;
    for (const Detection& d : detections)
      if (d.score >= t) kept.push_back(d);
    const PrecisionRecall expected = evaluate_detections(kept, truth);
    const PrecisionRecall& got = curve[i].result;
    EXPECT_EQ(curve[i].parameter, t);
    EXPECT_EQ(got.detections, expected.detections);
    EXPECT_EQ(got.true_positives, expected.true_positives);
    EXPECT_EQ(got.false_positives, expected.false_positives);
    EXPECT_EQ(got.queries_with_loops, expected.queries_with_loops);
    EXPECT_EQ(got.queries_found, expected.queries_found) << t;
    EXPECT_DOUBLE_EQ(got.precision, expected.precision);
    EXPECT_DOUBLE_EQ(got.recall, expected.recall);
    ++i;
  }
}

// A pair index far beyond any run ("49999999 0") costs what a small one does:
// before, 20,000 detections swept by score allocated and cleared a 50 MB
// vector per threshold (past 300 s); this finishes at once.
TEST(GroundTruth, FarIndicesAreStoredSparsely) {
  TempDir dir;
  write_text(dir.file("gt.txt"), "# 0-based\n49999999 0\n5 1\n");
  const GroundTruth truth = GroundTruth::load(dir.file("gt.txt"));
  EXPECT_EQ(truth.frames(), 50'000'000u);
  EXPECT_EQ(truth.pair_count(), 2u);
  EXPECT_TRUE(truth.is_loop(0, 49'999'999));
  EXPECT_TRUE(truth.has_loop(5));
  EXPECT_FALSE(truth.has_loop(49'999'998));
  EXPECT_EQ(truth.queries_with_loops(), 2u);
  std::vector<Detection> detections;
  for (std::size_t q = 0; q < 20'000; ++q)
    detections.push_back({q + 10, q, "", "", static_cast<double>(q), 12});
  detections.push_back({5, 1, "", "", 0.5, 12});
  const std::vector<PrCurvePoint> curve = pr_curve_by_score(detections, truth);
  ASSERT_EQ(curve.size(), detections.size());
  EXPECT_EQ(curve.front().result.true_positives, 1u);
  EXPECT_DOUBLE_EQ(curve.front().result.recall, 0.5);
}

// With the run's frame count, the ground truth is cut to it: pairs beyond are
// ignored, text pairs describe exactly that many frames, images and .mat
// matrices are read only that far.
TEST(GroundTruth, RunFramesCutTheGroundTruth) {
  TempDir dir;
  write_text(dir.file("gt.txt"), "# 0-based\n49999999 0\n5 1\n");
  GroundTruthOptions options;
  options.frames = 84;
  const GroundTruth text = GroundTruth::load(dir.file("gt.txt"), options);
  EXPECT_EQ(text.frames(), 84u);
  EXPECT_EQ(text.pair_count(), 1u);

  const GroundTruth full = GroundTruth::load(shared_data("rtabmap-samples/samples_GT.bmp"));
  options.frames = 40;
  const GroundTruth cut = GroundTruth::load(shared_data("rtabmap-samples/samples_GT.bmp"), options);
  EXPECT_EQ(cut.frames(), 40u);
  std::set<std::pair<std::size_t, std::size_t>> expected;
  for (const auto& [q, m] : loops_of(full))
    if (q < 40) expected.emplace(q, m);
  EXPECT_EQ(loops_of(cut), expected);

  const std::string mat = shared_data("lcd-groundtruth-knzhang/Lip6IndoorGroundTruth.mat");
  const GroundTruth mat_full = GroundTruth::load(mat);
  options.frames = 300;
  const GroundTruth mat_cut = GroundTruth::load(mat, options);
  EXPECT_EQ(mat_cut.frames(), 300u);
  expected.clear();
  for (const auto& [q, m] : loops_of(mat_full))
    if (q < 300) expected.emplace(q, m);
  EXPECT_EQ(loops_of(mat_cut), expected);
  EXPECT_FALSE(expected.empty());
}

TEST(GroundTruth, ImagesMustBeSquareAndWithinThePixelLimit) {
  TempDir dir;
  const std::string photo = shared_data("rtabmap-samples/samples/1.jpg");
  try {
    GroundTruth::load(photo);
    ADD_FAILURE() << "a 512x384 photograph accepted as ground truth";
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), photo);
    EXPECT_NE(std::string(e.what()).find("512x384"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("square"), std::string::npos) << e.what();
  }

  // An all-white PNG whose header says 20000x20000: refused before decoding
  // (it took more than 10 GB).
  ASSERT_TRUE(cv::imwrite(dir.file("white.png"), cv::Mat(64, 64, CV_8UC1, cv::Scalar(255))));
  std::vector<std::uint8_t> png = test::read_file(dir.file("white.png"));
  const std::uint8_t size[8] = {0, 0, 0x4E, 0x20, 0, 0, 0x4E, 0x20};
  std::copy(size, size + 8, png.begin() + 16);
  png.resize(434'000, 0);
  test::write_file(dir.file("white.png"), png);
  try {
    GroundTruth::load(dir.file("white.png"));
    ADD_FAILURE() << "decoded a 20000x20000 ground truth";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("declares 20000x20000 pixels, more than the limit"),
              std::string::npos)
        << e.what();
  }
}

TEST(GroundTruth, SpecialFilesAreRefusedWithoutBlocking) {
  TempDir dir;
  for (const char* name : {"gt.txt", "gt.mat", "gt.png", "loops.csv"})
    ASSERT_EQ(mkfifo(dir.file(name).c_str(), 0600), 0);
  for (const char* name : {"gt.txt", "gt.mat", "gt.png"}) {
    try {
      GroundTruth::load(dir.file(name));
      ADD_FAILURE() << "read a FIFO";
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find("is a FIFO"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(read_detections_csv(dir.file("loops.csv")), FileError);
}

TEST(Detections, NonFiniteScoresAreRefused) {
  TempDir dir;
  for (const char* score : {"nan", "inf", "-inf", "1e999"}) {
    write_text(dir.file("a.csv"),
               std::string("query_index,match_index,query_file,match_file,score,inliers\n"
                           "1,0,a,b,") +
                   score + ",12\n");
    EXPECT_THROW(read_detections_csv(dir.file("a.csv")), FileError) << score;
  }
}

// A loop closes with an earlier frame: detect-loops never writes a row whose
// match is the query or later, so such a row is a damaged or foreign file.
TEST(DetectionsCsv, RowsWhoseMatchIsNotEarlierAreRefusedNamingTheLine) {
  test::TempDir dir;
  const std::string header = "query_index,match_index,query_file,match_file,score,inliers\n";
  for (const std::string row : {"4,4,a.jpg,a.jpg,0.5,30\n", "4,9,a.jpg,b.jpg,0.5,30\n"}) {
    SCOPED_TRACE(row);
    std::ofstream(dir.file("loops.csv")) << header << "5,2,c.jpg,d.jpg,0.5,30\n" << row;
    try {
      read_detections_csv(dir.file("loops.csv"));
      ADD_FAILURE() << "read";
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), dir.file("loops.csv"));
      EXPECT_NE(std::string(e.what()).find("line 3: match"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("not earlier than query 4"), std::string::npos)
          << e.what();
    }
  }
}

// Loops found by another tool: any CSV whose header names query and match.
TEST(DetectionsCsv, AnyCsvWithQueryAndMatchColumnsIsRead) {
  test::TempDir dir;
  std::ofstream(dir.file("other.csv")) << "Score, Match ,frame_time,QUERY\n"
                                       << "0.75,2,1.5,5\n"
                                       << " 0.5 , 0 ,2.5, 9 \n";
  const std::vector<Detection> read = read_detections_csv(dir.file("other.csv"));
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0].query, 5u);
  EXPECT_EQ(read[0].match, 2u);
  EXPECT_EQ(read[0].score, 0.75);
  EXPECT_EQ(read[0].inliers, 0u);
  EXPECT_EQ(read[1].query, 9u);
  EXPECT_EQ(read[1].match, 0u);

  std::ofstream(dir.file("pairs.csv")) << "query,match\n7,3\n";
  ASSERT_EQ(read_detections_csv(dir.file("pairs.csv")).size(), 1u);

  const auto expect_refused = [&](const std::string& text, const std::string& what) {
    SCOPED_TRACE(text);
    std::ofstream(dir.file("bad.csv")) << text;
    try {
      read_detections_csv(dir.file("bad.csv"));
      ADD_FAILURE() << "read";
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), dir.file("bad.csv"));
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_refused("a,b\n1,0\n", "line 1: expected a header naming a query and a match column");
  expect_refused("query,match,query\n1,0,1\n", "names the column \"query\" twice");
  expect_refused("query,match\n1,0,4\n", "line 2: expected 2 comma-separated fields");
  expect_refused("query,match\n1,x\n", "line 2: \"x\" is not a non-negative index");
  expect_refused("query,match\n3,3\n", "line 2: match 3 is not earlier than query 3");
}

}  // namespace
}  // namespace binbow::loop
