// Explaining the misses: the missed-loop and false-loop lists against a
// hand-made ground truth, the binned similarity matrix against scores computed pair by pair,
// the precision–recall curve's drawing order, the sweepable parameters, the
// run record's correspondences, and the report page that shows them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "binbow/error.h"
#include "binbow/loop/false_loops.h"
#include "binbow/loop/misses.h"
#include "binbow/loop/report.h"
#include "binbow/loop/run_record.h"
#include "binbow/loop/similarity.h"
#include "binbow/loop/sweep.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// 12 frames; queries 5, 6, 7, 9 and 11 share a place with earlier images.
GroundTruth hand_made_truth() {
  return GroundTruth(12, {{5, 0}, {5, 1}, {6, 1}, {7, 2}, {9, 3}, {11, 4}});
}

FrameRecord frame(const std::string& status, long long match, std::size_t inliers,
                  long long correspondences) {
  FrameRecord record;
  record.file = "f.png";
  record.status = status;
  record.match = match;
  record.score = 0.1;
  record.normalised_score = 0.5;
  record.inliers = inliers;
  record.correspondences = correspondences;
  return record;
}

TEST(MissedLoops, EveryQueryWithAGroundTruthLoopAndNoTrueDetection) {
  const GroundTruth truth = hand_made_truth();
  std::vector<FrameRecord> frames(12, frame("no-database-results", -1, 0, 0));
  frames[5] = frame("loop-detected", 0, 30, 40);             // found
  frames[6] = frame("no-geometric-consistency", 1, 7, 13);   // right candidate, too few inliers
  frames[7] = frame("no-temporal-consistency", 0, 0, 0);     // wrong candidate, never verified
  frames[9] = frame("loop-detected", 8, 20, 25);             // a false loop
  frames[11] = frame("low-normalisation-score", -1, 0, -1);  // record without correspondences
  const std::vector<Detection> detections = {{5, 0, "", "", 0.5, 30}, {9, 8, "", "", 0.5, 20}};

  std::vector<MissedLoop> missed = missed_loops(frames, detections, truth);
  ASSERT_EQ(missed.size(), 4u);
  EXPECT_EQ(missed[0].query, 6u);
  EXPECT_EQ(missed[0].status, "no-geometric-consistency");
  EXPECT_EQ(missed[0].match, 1);
  EXPECT_EQ(missed[0].candidate_right, 1);
  EXPECT_EQ(missed[0].correspondences, 13);
  EXPECT_EQ(missed[0].inliers, 7);
  EXPECT_EQ(missed[1].query, 7u);
  EXPECT_EQ(missed[1].candidate_right, 0);
  EXPECT_FALSE(geometrically_checked(missed[1]));
  EXPECT_EQ(missed[2].query, 9u);
  EXPECT_EQ(missed[2].status, "loop-detected");
  EXPECT_EQ(missed[2].candidate_right, 0);
  EXPECT_EQ(missed[3].query, 11u);
  EXPECT_EQ(missed[3].match, -1);
  EXPECT_EQ(missed[3].candidate_right, -1);

  EXPECT_EQ(format_missed_loop(missed[0]),
            "  query 6: no-geometric-consistency, candidate 1 (right), 13 correspondences, 7 "
            "inliers");
  EXPECT_EQ(format_missed_loop(missed[1]),
            "  query 7: no-temporal-consistency, candidate 0 (wrong), not checked geometrically");
  EXPECT_EQ(format_missed_loop(missed[3]), "  query 11: low-normalisation-score, no candidate");
  missed[0].correspondences = -1;
  EXPECT_EQ(format_missed_loop(missed[0]),
            "  query 6: no-geometric-consistency, candidate 1 (right), correspondences unknown, 7 "
            "inliers");
  // A record that knows the frame's features says how many there were.
  frames[11].features = 0;
  EXPECT_EQ(format_missed_loop(missed_loops(frames, detections, truth)[3]),
            "  query 11: low-normalisation-score, no candidate, 0 features");
}

TEST(MissedLoops, WithoutARunRecordOnlyTheDetectionsAreKnown) {
  const GroundTruth truth = hand_made_truth();
  const std::vector<Detection> detections = {{5, 0, "", "", 0.5, 30}, {9, 8, "q9", "", 0.5, 20}};
  const std::vector<MissedLoop> missed = missed_loops({}, detections, truth);
  ASSERT_EQ(missed.size(), 4u);
  EXPECT_EQ(missed[0].query, 6u);
  EXPECT_EQ(format_missed_loop(missed[0]), "  query 6: status unknown, candidate unknown");
  EXPECT_EQ(missed[2].query, 9u);
  EXPECT_EQ(missed[2].file, "q9");
  EXPECT_EQ(format_missed_loop(missed[2]),
            "  query 9: loop-detected, candidate 8 (wrong), correspondences unknown, 20 inliers");
  EXPECT_THROW(missed_loops({}, {{12, 0, "", "", 1, 12}}, truth), InvalidArgument);
}

TEST(FalseLoops, EveryDetectionTheGroundTruthDoesNotHoldWithItsEvidence) {
  const GroundTruth truth = hand_made_truth();
  std::vector<FrameRecord> frames(12, frame("no-database-results", -1, 0, 0));
  frames[5] = frame("loop-detected", 0, 30, 40);
  frames[5].accepted_by = "strong-fit";
  frames[9] = frame("loop-detected", 8, 20, 25);
  frames[9].accepted_by = "revisit-pace";
  frames[10] = frame("loop-detected", 2, 18, 20);
  frames[10].accepted_by = "strong-fit";
  frames[10].localised_from = 3;
  const std::vector<Detection> detections = {
      {5, 0, "", "", 0.5, 30}, {9, 8, "q9", "", 0.4, 20}, {10, 2, "", "", 0.3, 18}};

  const std::vector<FalseLoop> wrong = false_loops(frames, detections, truth);
  ASSERT_EQ(wrong.size(), 2u);
  EXPECT_EQ(wrong[0].query, 9u);
  EXPECT_EQ(wrong[0].match, 8u);
  EXPECT_EQ(wrong[0].file, "q9");
  EXPECT_EQ(format_false_loop(wrong[0]),
            "  query 9: match 8, 20 inliers, accepted by revisit-pace");
  EXPECT_EQ(wrong[1].file, "f.png");
  EXPECT_EQ(format_false_loop(wrong[1]),
            "  query 10: match 2, 18 inliers, accepted by strong-fit, localised from 3");

  // Without a record, or with one whose frame names another match (not this
  // run's), the evidence is not known.
  EXPECT_EQ(format_false_loop(false_loops({}, detections, truth)[0]),
            "  query 9: match 8, 20 inliers, evidence unknown");
  frames[9].match = 7;
  EXPECT_EQ(false_loops(frames, detections, truth)[0].accepted_by, "");
  EXPECT_THROW(false_loops({}, {{12, 0, "", "", 1, 12}}, truth), InvalidArgument);
}

Vocabulary small_vocabulary(std::mt19937_64& rng) {
  std::vector<DescriptorMatrix> images;
  for (int i = 0; i < 30; ++i) images.push_back(test::random_descriptors(100, 32, rng));
  BuildOptions options;
  options.branching = 8;
  options.levels = 3;
  options.threads = 1;
  return Vocabulary::build(std::vector<DescriptorView>(images.begin(), images.end()), options);
}

std::vector<vision::Features> random_frames(std::size_t count, std::mt19937_64& rng,
                                            std::size_t features = 4) {
  std::vector<vision::Features> frames(count);
  for (vision::Features& f : frames) {
    f.descriptors = test::random_descriptors(features, 32, rng);
    f.keypoints.resize(features);
  }
  return frames;
}

// The highest pairwise score of the frames in two bins, j < i, computed pair by pair.
float expected_cell(const Vocabulary& vocabulary, const std::vector<BowVector>& bows,
                    const SimilarityMatrix& m, std::size_t row, std::size_t column,
                    std::size_t row_stride) {
  float best = 0;
  for (std::size_t i = row * m.bin; i < std::min(m.frames, (row + 1) * m.bin); ++i) {
    if (i % row_stride != 0) continue;
    for (std::size_t j = column * m.bin; j < std::min(i, (column + 1) * m.bin); ++j)
      best = std::max(best, static_cast<float>(vocabulary.score(bows[i], bows[j])));
  }
  return best;
}

std::vector<BowVector> transform_all(const Vocabulary& vocabulary,
                                     const std::vector<vision::Features>& frames) {
  std::vector<BowVector> bows(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i)
    vocabulary.transform(frames[i].descriptors, bows[i]);
  return bows;
}

TEST(SimilarityMatrix, ShortSequencesHaveOneCellPerPair) {
  std::mt19937_64 rng(7);
  const Vocabulary vocabulary = small_vocabulary(rng);
  const std::vector<vision::Features> frames = random_frames(30, rng, 20);
  const SimilarityMatrix m = similarity_matrix(vocabulary, frames);
  ASSERT_EQ(m.frames, 30u);
  ASSERT_EQ(m.bin, 1u);
  ASSERT_EQ(m.cells, 30u);
  EXPECT_TRUE(m.every_query);
  const std::vector<BowVector> bows = transform_all(vocabulary, frames);
  std::size_t positive = 0;
  for (std::size_t i = 0; i < 30; ++i)
    for (std::size_t j = 0; j < 30; ++j) {
      const float expected = j < i ? static_cast<float>(vocabulary.score(bows[i], bows[j])) : 0;
      EXPECT_EQ(m.at(i, j), expected) << i << ", " << j;
      positive += expected > 0;
    }
  EXPECT_GT(positive, 100u) << "the test needs frames that share words";

  // The same from a loop detector that processed the frames.
  LoopDetector detector(vocabulary);
  for (const vision::Features& f : frames) detector.process(f);
  EXPECT_EQ(similarity_matrix(detector).scores, m.scores);
  LoopDetectorParams no_check;
  no_check.geometric_check = GeometricCheck::kNone;
  EXPECT_THROW(similarity_matrix(LoopDetector(vocabulary, no_check)), InvalidArgument);
  EXPECT_TRUE(similarity_matrix(vocabulary, std::vector<vision::Features>{}).empty());
}

TEST(SimilarityMatrix, LongSequencesAreBinnedByTheirHighestScore) {
  std::mt19937_64 rng(11);
  const Vocabulary vocabulary = small_vocabulary(rng);
  const std::vector<vision::Features> frames = random_frames(2100, rng);
  const SimilarityMatrix m = similarity_matrix(vocabulary, frames);
  ASSERT_EQ(m.bin, 3u);  // ⌈2100 / 1000⌉
  ASSERT_EQ(m.cells, 700u);
  EXPECT_TRUE(m.every_query);
  const std::vector<BowVector> bows = transform_all(vocabulary, frames);
  std::size_t positive = 0;
  for (const std::size_t row : {0u, 1u, 350u, 699u})
    for (std::size_t column = 0; column < m.cells; ++column) {
      ASSERT_EQ(m.at(row, column), expected_cell(vocabulary, bows, m, row, column, 1))
          << row << ", " << column;
      positive += m.at(row, column) > 0;
    }
  EXPECT_GT(positive, 100u) << "the test needs frames that share words";
}

TEST(SimilarityMatrix, VeryLongSequencesScoreSampledQueryRows) {
  std::mt19937_64 rng(13);
  const Vocabulary vocabulary = small_vocabulary(rng);
  const std::vector<vision::Features> frames = random_frames(kMaxSimilarityQueries + 1, rng);
  const SimilarityMatrix m = similarity_matrix(vocabulary, frames);
  EXPECT_FALSE(m.every_query);
  ASSERT_EQ(m.bin, 6u);
  const std::vector<BowVector> bows = transform_all(vocabulary, frames);
  std::size_t positive = 0;
  for (const std::size_t row : {1u, 500u, 833u})
    for (std::size_t column = 0; column <= row; ++column) {
      ASSERT_EQ(m.at(row, column), expected_cell(vocabulary, bows, m, row, column, 2))
          << row << ", " << column;
      positive += m.at(row, column) > 0;
    }
  EXPECT_GT(positive, 100u) << "the test needs frames that share words";
}

PrCurvePoint point(double parameter, double precision, double recall) {
  PrCurvePoint p;
  p.parameter = parameter;
  p.result.precision = precision;
  p.result.recall = recall;
  p.result.detections = recall > 0 ? 10 : 0;
  p.result.false_positives = precision < 1 ? 1 : 0;
  p.result.true_positives = p.result.detections - p.result.false_positives;
  return p;
}

TEST(PrCurve, DrawnInRecallOrderAndFullPrecisionNamesItsValue) {
  const std::vector<PrCurvePoint> curve = {point(0.1, 0.9, 0.8), point(0.2, 1, 0.7),
                                           point(0.3, 1, 0.7),   point(0.4, 1, 0.5),
                                           point(0.5, 1, 0),     point(0.05, 0.8, 0.8)};
  std::vector<double> order;
  for (const PrCurvePoint& p : curve_in_recall_order(curve)) order.push_back(p.parameter);
  EXPECT_EQ(order, (std::vector<double>{0.5, 0.4, 0.2, 0.3, 0.1, 0.05}));
  const PrCurvePoint* best = full_precision_point(curve);
  ASSERT_NE(best, nullptr);
  EXPECT_EQ(best->parameter, 0.3);  // of two equal recalls, the later (stricter) value
  EXPECT_EQ(recall_at_full_precision(curve), best->result.recall);
  EXPECT_EQ(full_precision_point({point(0.1, 0.9, 0.8)}), nullptr);
}

TEST(Sweep, ParametersAndTheirDefaultValues) {
  const std::vector<std::string> names = sweepable_parameters();
  for (const char* name :
       {"alpha", "k", "min_inliers", "max_reprojection_error", "max_neighbor_ratio", "dislocal"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
    EXPECT_GE(default_sweep_values(name).size(), 5u) << name;
  }
  // Every sweepable parameter has defaults, all valid.
  for (const std::string& name : names) EXPECT_NO_THROW(sweep_values(name)) << name;
  EXPECT_EQ(std::find(names.begin(), names.end(), "frequency"), names.end());
  EXPECT_EQ(default_sweep_values("alpha"), default_alpha_values());
  EXPECT_EQ(sweep_values("k", {1, 2}), (std::vector<double>{1, 2}));
  try {
    sweep_values("bogus");
    FAIL() << "an unknown parameter was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("choices: alpha"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("min_inliers"), std::string::npos) << e.what();
  }
  EXPECT_THROW(sweep_values("k", {1.5}), InvalidArgument);
  EXPECT_THROW(sweep_values("min_inliers", {3}), InvalidArgument);
  EXPECT_THROW(sweep_values("use_normalised_score"), InvalidArgument);
}

LoopRun run_description() {
  LoopRun run;
  run.inputs = {"/nowhere"};
  run.vocabulary = "/nowhere.bbw";
  run.descriptor = "orb";
  run.params_json = LoopDetectorParams{}.to_json();
  return run;
}

TEST(RunRecord, KeepsItsProvenanceAndReadsRecordsWithout) {
  test::TempDir dir;
  const std::string csv = dir.file("loops.csv");
  LoopRun description = run_description();
  description.provenance = {"9.8.7", "2026-11-29T10:26:19Z", "binbow detect-loops -o 'a b.csv' f"};
  {
    LoopRunFiles files(csv, description);
    files.add(SequenceFrame{});
    files.commit();
  }
  const std::string record = LoopRun::path_for(csv);
  const LoopRun run = LoopRun::load(record);
  EXPECT_EQ(run.provenance.binbow_version, "9.8.7");
  EXPECT_EQ(run.provenance.date, "2026-11-29T10:26:19Z");
  EXPECT_EQ(run.provenance.command, "binbow detect-loops -o 'a b.csv' f");
  // Written only when known: a record without it reads as before.
  {
    LoopRunFiles files(csv, run_description());
    files.add(SequenceFrame{});
    files.commit();
  }
  EXPECT_EQ(read_text(record).find("provenance"), std::string::npos);
  EXPECT_TRUE(LoopRun::load(record).provenance.empty());
}

TEST(RunRecord, KeepsEachFramesCorrespondencesAndReadsOlderRecords) {
  test::TempDir dir;
  const std::string csv = dir.file("loops.csv");
  {
    LoopRunFiles files(csv, run_description());
    SequenceFrame f;
    f.file = "a.png";
    f.result.status = LoopStatus::kNoGeometricConsistency;
    f.result.has_candidate = true;
    f.result.match = 0;
    f.result.correspondences = 13;
    f.result.features = 26;
    f.result.inliers.resize(7);
    files.add(f);
    files.commit();
  }
  const std::string record = LoopRun::path_for(csv);
  const LoopRun run = LoopRun::load(record);
  ASSERT_EQ(run.frames.size(), 1u);
  EXPECT_EQ(run.frames[0].correspondences, 13);
  EXPECT_EQ(run.frames[0].inliers, 7u);
  EXPECT_EQ(run.frames[0].features, 26);

  std::string text = read_text(record);
  const std::string key = "\"correspondences\":13,";
  ASSERT_NE(text.find(key), std::string::npos) << text;
  std::string older = text;
  older.erase(older.find(key), key.size());
  std::ofstream(record, std::ios::binary) << older;
  EXPECT_EQ(LoopRun::load(record).frames[0].correspondences, -1);
  const std::string features_key = "\"features\":26,";
  ASSERT_NE(older.find(features_key), std::string::npos) << older;
  older.erase(older.find(features_key), features_key.size());
  std::ofstream(record, std::ios::binary | std::ios::trunc) << older;
  EXPECT_EQ(LoopRun::load(record).frames[0].features, -1);

  std::string negative = text;
  negative.replace(negative.find(key), key.size(), "\"correspondences\":-5,");
  std::ofstream(record, std::ios::binary | std::ios::trunc) << negative;
  EXPECT_THROW(LoopRun::load(record), FileError);

  // Found by fuzzing: a match of -5.6e35 was converted to long long
  // (undefined behaviour); fractions and values out of range are refused.
  const std::string match_key = "\"match\":0,";
  ASSERT_NE(text.find(match_key), std::string::npos) << text;
  for (const std::string value : {"-5.6e35", "1.5", "9223372036854775808"}) {
    std::string bad = text;
    bad.replace(bad.find(match_key), match_key.size(), "\"match\":" + value + ",");
    std::ofstream(record, std::ios::binary | std::ios::trunc) << bad;
    try {
      LoopRun::load(record);
      ADD_FAILURE() << "loaded a match of " << value;
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find("\"match\" is "), std::string::npos) << e.what();
    }
  }
}

TEST(LoopReport, PageShowsMissesSimilaritySweepTable) {
  std::mt19937_64 rng(3);
  const Vocabulary vocabulary = small_vocabulary(rng);
  const GroundTruth truth = hand_made_truth();

  std::vector<SequenceFrame> frames(12);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    frames[i].file = "frame" + std::to_string(i) + ".png";
    frames[i].result.query = static_cast<EntryId>(i);
  }
  frames[5].result.status = LoopStatus::kLoopDetected;
  frames[5].result.has_candidate = true;
  frames[5].result.match = 0;
  frames[6].result.status = LoopStatus::kNoGeometricConsistency;
  frames[6].result.has_candidate = true;
  frames[6].result.match = 1;
  frames[6].result.correspondences = 13;
  const SimilarityMatrix similarity = similarity_matrix(vocabulary, random_frames(12, rng));
  LoopReport report = make_loop_report(frames, LoopDetectorParams{}, &truth, similarity);
  ASSERT_EQ(report.missed.size(), 4u);  // 6, 7, 9, 11
  EXPECT_EQ(report.missed[0].correspondences, 13);
  report.curve = {point(0.2, 1, 0.2), point(0.3, 1, 0.4), point(0.4, 0.5, 0.6)};
  report.curve_parameter = "alpha";
  report.recall_at_full_precision = 0.4;

  test::TempDir dir;
  const std::string page = write_loop_report(dir.file("report"), report);
  const std::string html = read_text(page);
  for (const char* part : {"id='missed'", "id='missed-6'", "id='missed-11'", "id='sweep'",
                           "id='similarity'", "data:image/png;base64,", "reached at α = 0.3",
                           "α=0.4", "no-geometric-consistency", "class='best'"})
    EXPECT_NE(html.find(part), std::string::npos) << part;
  EXPECT_EQ(html.find("id='missed-5'"), std::string::npos) << "query 5 was found";

  const cv::Mat png = cv::imread(dir.file("report/similarity.png"), cv::IMREAD_COLOR);
  ASSERT_FALSE(png.empty());
  EXPECT_GE(png.cols, 700);
  EXPECT_EQ(similarity_png(report).size(),
            std::filesystem::file_size(dir.file("report/similarity.png")));

  // Without a matrix there is no figure, and nothing else changes.
  report.similarity = {};
  const std::string plain = read_text(write_loop_report(dir.file("plain"), report));
  EXPECT_EQ(plain.find("id='similarity'"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir.file("plain/similarity.png")));
  EXPECT_NE(plain.find("id='missed'"), std::string::npos);
}

// The precision–recall chart of a page: its <svg> element.
std::string pr_chart(const std::string& html) {
  const std::size_t start = html.find("<svg");
  if (start == std::string::npos) return "";
  return html.substr(start, html.find("</svg>", start) - start);
}

std::size_t occurrences(const std::string& text, const std::string& part) {
  std::size_t n = 0;
  for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
  return n;
}

TEST(PrCurveChart, LegendNamesOnlyTheMarksDrawn) {
  LoopReport report;
  report.curve = {point(0.2, 0.9, 0.3), point(0.3, 0.8, 0.5)};  // never 100% precision
  report.curve_parameter = "alpha";
  test::TempDir dir;
  std::string chart = pr_chart(read_text(write_loop_report(dir.file("a"), report)));
  ASSERT_FALSE(chart.empty());
  EXPECT_EQ(occurrences(chart, "<g class='legend'>"), 1u) << chart;
  EXPECT_NE(chart.find("swept α"), std::string::npos);
  EXPECT_EQ(chart.find("this run"), std::string::npos) << "no run result is drawn";
  EXPECT_EQ(chart.find("highest recall at 100% precision"), std::string::npos)
      << "no point has 100% precision";

  report.has_result = true;
  report.result.precision = 1;
  report.result.recall = 0.5;
  report.curve.push_back(point(0.4, 1, 0.5));
  chart = pr_chart(read_text(write_loop_report(dir.file("b"), report)));
  EXPECT_EQ(occurrences(chart, "<g class='legend'>"), 3u) << chart;
  EXPECT_NE(chart.find("id='full-precision-point'"), std::string::npos);
  EXPECT_NE(chart.find("highest recall at 100% precision"), std::string::npos);
  EXPECT_NE(chart.find("this run"), std::string::npos);
}

TEST(PrCurveChart, PointLabelsStayInsideThePlotAndApart) {
  LoopReport report;
  report.curve_parameter = "alpha";
  report.curve = {point(0.1, 0.05, 0.9), point(0.2, 0.3, 0.8), point(0.3, 0.6, 0.6),
                  point(0.4, 0.95, 0.3), point(0.5, 1, 0.1)};
  test::TempDir dir;
  const std::string chart = pr_chart(read_text(write_loop_report(dir.file("r"), report)));
  double left = 0, top = 0, width = 0, height = 0;
  ASSERT_EQ(
      std::sscanf(chart.c_str() + chart.find("<rect "),
                  "<rect x='%lf' y='%lf' width='%lf' height='%lf'", &left, &top, &width, &height),
      4)
      << chart;
  std::vector<std::pair<double, double>> anchors;
  for (std::size_t at = chart.find("class='pt'"); at != std::string::npos;
       at = chart.find("class='pt'", at + 1)) {
    double x = 0, y = 0, angle = 0;
    const std::size_t transform = chart.find("translate(", at);
    ASSERT_EQ(
        std::sscanf(chart.c_str() + transform, "translate(%lf %lf) rotate(%lf)", &x, &y, &angle),
        3);
    const std::size_t begin = chart.find('>', at) + 1;
    const std::string label = chart.substr(begin, chart.find('<', begin) - begin);
    std::size_t characters = 0;  // UTF-8: count the lead bytes
    for (const char c : label) characters += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    // Rotated by ±90°, a label runs down or up from its anchor; at 10 px,
    // a character takes at most about 6 px.
    const double end = y + (angle > 0 ? 1 : -1) * 6.0 * static_cast<double>(characters);
    EXPECT_GE(std::min(y, end), top) << label;
    EXPECT_LE(std::max(y, end), top + height) << label << " runs into the axis labels";
    for (const auto& [other_x, other_y] : anchors)
      EXPECT_FALSE(std::abs(other_x - x) < 10 && std::abs(other_y - y) < 10) << label;
    anchors.emplace_back(x, y);
  }
  EXPECT_EQ(anchors.size(), report.curve.size());
}

// The texts of the chart's point labels, in the order drawn.
std::vector<std::string> point_labels(const std::string& chart) {
  std::vector<std::string> labels;
  for (std::size_t at = chart.find("class='pt'"); at != std::string::npos;
       at = chart.find("class='pt'", at + 1)) {
    const std::size_t begin = chart.find('>', at) + 1;
    labels.push_back(chart.substr(begin, chart.find('<', begin) - begin));
  }
  return labels;
}

TEST(PrCurveChart, EachPointIsLabelledWithItsOwnValues) {
  LoopReport report;
  report.curve_parameter = "alpha";
  // 0.5 and 0.8 to 1 land on one point; 0.6 and 0.7, between them in the
  // sweep, land elsewhere: a label "α=0.5–1" would claim them too.
  report.curve = {point(0.5, 1, 0.4), point(0.6, 1, 0.5), point(0.7, 0.9, 0.6),
                  point(0.8, 1, 0.4), point(0.9, 1, 0.4), point(1.0, 1, 0.4)};
  test::TempDir dir;
  const std::string chart = pr_chart(read_text(write_loop_report(dir.file("r"), report)));
  EXPECT_EQ(point_labels(chart), (std::vector<std::string>{"α=0.5, 0.8–1", "α=0.6", "α=0.7"}))
      << chart;
  // Two neighbours are listed, not made a range.
  report.curve = {point(0.2, 1, 0.4), point(0.3, 1, 0.4), point(0.4, 0.9, 0.6)};
  EXPECT_EQ(point_labels(pr_chart(read_text(write_loop_report(dir.file("s"), report)))),
            (std::vector<std::string>{"α=0.2, 0.3", "α=0.4"}));
}

// Pixels of the similarity figure in the red of false loops.
std::size_t red_pixels(const std::vector<unsigned char>& png) {
  const cv::Mat image = cv::imdecode(png, cv::IMREAD_COLOR);
  std::size_t n = 0;
  for (int r = 0; r < image.rows; ++r)
    for (int c = 0; c < image.cols; ++c) {
      const cv::Vec3b& p = image.at<cv::Vec3b>(r, c);  // BGR
      n += p[2] > 180 && p[1] < 90 && p[0] < 90;
    }
  return n;
}

TEST(SimilarityFigure, LegendShowsOnlyTheMarksDrawn) {
  std::mt19937_64 rng(5);
  const Vocabulary vocabulary = small_vocabulary(rng);
  const GroundTruth truth = hand_made_truth();
  std::vector<SequenceFrame> frames(12);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    frames[i].file = "frame" + std::to_string(i) + ".png";
    frames[i].result.query = static_cast<EntryId>(i);
  }
  frames[5].result.status = LoopStatus::kLoopDetected;
  frames[5].result.has_candidate = true;
  frames[5].result.match = 0;
  LoopReport report = make_loop_report(frames, LoopDetectorParams{}, &truth,
                                       similarity_matrix(vocabulary, random_frames(12, rng)));
  ASSERT_EQ(report.loops.size(), 1u);
  ASSERT_EQ(report.loops[0].verdict, 1);
  EXPECT_EQ(red_pixels(similarity_png(report)), 0u) << "a false-loop mark with no false loop";
  report.loops[0].verdict = 0;
  EXPECT_GT(red_pixels(similarity_png(report)), 0u);
}

}  // namespace
}  // namespace binbow::loop
