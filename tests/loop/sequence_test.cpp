// The library's sequence runner, run files, sweep and report: what
// detect-loops, evaluate and Python's detect_loops share.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/loop/report.h"
#include "binbow/loop/run_record.h"
#include "binbow/loop/sequence.h"
#include "binbow/loop/sweep.h"
#include "loop/same_result.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

namespace fs = std::filesystem;

Vocabulary brief_vocabulary() {
  return load_vocabulary(test::source_path("data/vocab/brief_default.bbw"));
}

SequenceOptions brief_options() {
  SequenceOptions options;
  options.descriptor = "brief";
  return options;
}

std::vector<std::string> samples() {
  return {test::samples_folder()};
}

TEST(Sequence, EqualsTheDetectorRunFrameByFrame) {
  SequenceDetector sequence(samples(), brief_vocabulary(), brief_options());
  const std::vector<SequenceFrame> frames = detect_sequence(sequence);
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(sequence.size()));

  const auto extractor = vision::make_extractor("brief");
  LoopDetector detector(brief_vocabulary(), sequence.params());
  vision::ImageSource source(samples());
  vision::Frame frame;
  std::size_t i = 0, loops = 0;
  StatusCounts counts{};
  while (source.next(frame)) {
    ASSERT_LT(i, frames.size());
    const LoopResult expected = detector.process(extractor->extract(frame.image));
    const SequenceFrame& got = frames[i++];
    EXPECT_EQ(got.file, frame.name);
    EXPECT_EQ(got.result.status, expected.status) << got.file;
    EXPECT_EQ(got.result.match, expected.match) << got.file;
    EXPECT_EQ(got.result.inliers, expected.inliers) << got.file;
    ++counts[static_cast<std::size_t>(expected.status)];
    if (expected.detection()) {
      ++loops;
      EXPECT_EQ(got.match_file, frames[expected.match].file);
      EXPECT_EQ(got.inlier_points.size(), expected.inliers.size());
    } else {
      EXPECT_TRUE(got.match_file.empty());
      EXPECT_TRUE(got.inlier_points.empty());
    }
  }
  EXPECT_EQ(i, frames.size());
  EXPECT_GT(loops, 0u) << "the bundled sample closes loops";
  EXPECT_EQ(sequence.status_counts(), counts);
  EXPECT_EQ(sequence.frequency_origin(), "the paper's default; images have no frame rate");
}

TEST(Sequence, AnyNumberOfThreadsGivesOneThreadsRun) {
  SequenceOptions one_thread = brief_options();
  one_thread.threads = 1;
  one_thread.source.max_width = 400;  // a scale, so that inliers are converted
  SequenceDetector one(samples(), brief_vocabulary(), one_thread);
  const std::vector<SequenceFrame> expected = detect_sequence(one);
  std::size_t loops = 0;
  for (const SequenceFrame& frame : expected) loops += frame.result.detection();
  ASSERT_GT(loops, 5u) << "too few loops to compare";
  for (const unsigned threads : {2u, 5u}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    SequenceOptions options = one_thread;
    options.threads = threads;
    SequenceDetector many(samples(), brief_vocabulary(), options);
    const std::vector<SequenceFrame> got = detect_sequence(many);
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      test::expect_same_result(got[i].result, expected[i].result);
      EXPECT_EQ(got[i].file, expected[i].file);
      EXPECT_EQ(got[i].match_file, expected[i].match_file);
      EXPECT_EQ(got[i].inlier_points, expected[i].inlier_points);
    }
    EXPECT_EQ(many.status_counts(), one.status_counts());
    EXPECT_EQ(many.detector().size(), one.detector().size());
  }
}

TEST(Sequence, InlierPointsAreInPixelsOfTheFiles) {
  SequenceOptions halved = brief_options();
  halved.source.max_width = 256;  // the sample's frames are 512 wide
  SequenceDetector sequence(samples(), brief_vocabulary(), halved);
  bool checked = false;
  SequenceFrame frame;
  while (sequence.next(frame)) {
    for (const auto& p : frame.inlier_points) {
      // Keypoints of the 256-wide frames lie in [0, 256); their file pixels go up to 512.
      EXPECT_LT(p[0], 512.f);
      EXPECT_LT(p[2], 512.f);
      checked = checked || p[0] >= 256.f || p[2] >= 256.f;
    }
  }
  EXPECT_TRUE(checked) << "no inlier beyond the scaled frame: the scale was not undone";
}

TEST(Sequence, GivenParametersWinAndTheVocabularyMustFitTheDescriptor) {
  LoopDetectorParams params;
  params.alpha = 0.5;
  SequenceDetector sequence(samples(), brief_vocabulary(), brief_options(), params);
  EXPECT_EQ(sequence.params().alpha, 0.5);
  EXPECT_EQ(sequence.frequency_origin(), "the parameters given");

  SequenceOptions akaze;
  akaze.descriptor = "akaze";  // 61-byte descriptors against 32-byte words
  try {
    SequenceDetector wrong(samples(), brief_vocabulary(), akaze);
    FAIL() << "an AKAZE sequence accepted a BRIEF vocabulary";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("akaze"), std::string::npos) << e.what();
  }
}

TEST(Sequence, NoCandidateReasonNamesDislocal) {
  LoopDetectorParams params;
  EXPECT_EQ(no_candidate_reason(params, 22), "");
  EXPECT_NE(no_candidate_reason(params, 21).find("dislocal = 20"), std::string::npos);
}

TEST(LoopRunFiles, NothingAppearsWithoutCommit) {
  test::TempDir dir;
  const std::string csv = dir.file("out/loops.csv");
  fs::create_directories(dir.file("out"));
  LoopRun description;
  description.params_json = LoopDetectorParams{}.to_json();
  SequenceDetector sequence(samples(), brief_vocabulary(), brief_options());
  {
    LoopRunFiles files(csv, description);
    SequenceFrame frame;
    for (int i = 0; i < 3 && sequence.next(frame); ++i) files.add(frame);
  }
  EXPECT_FALSE(fs::exists(csv));
  EXPECT_FALSE(fs::exists(LoopRun::path_for(csv)));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.file("out")), fs::directory_iterator()), 0)
      << "temporaries left behind";

  LoopRunFiles files(csv, description);
  SequenceFrame frame;
  while (sequence.next(frame)) files.add(frame);
  files.commit();
  const LoopRun run = LoopRun::load(LoopRun::path_for(csv));
  EXPECT_EQ(run.frames.size(), files.frames());
  EXPECT_EQ(read_detections_csv(csv).size(), files.detections().size());
  ASSERT_EQ(run.timing.size(), kStageCount);
  EXPECT_EQ(run.timing[0].stage, "features");
}

TEST(Sweep, RefusesUnknownParametersAndFractionsOfWholeNumbers) {
  LoopRun run;
  run.params_json = LoopDetectorParams{}.to_json();
  const Vocabulary vocabulary = brief_vocabulary();
  const GroundTruth truth(2, {});
  EXPECT_THROW(sweep_parameter(run, vocabulary, truth, "nonsense", {1}), InvalidArgument);
  EXPECT_THROW(sweep_parameter(run, vocabulary, truth, "geometric_check", {1}), InvalidArgument);
  EXPECT_THROW(sweep_parameter(run, vocabulary, truth, "k", {1.5}), InvalidArgument);
  EXPECT_THROW(sweep_parameter(run, vocabulary, truth, "alpha", {-1}), InvalidArgument);
}

TEST(Report, OfASequenceGivesVerdictsAgainstGroundTruth) {
  SequenceDetector sequence(samples(), brief_vocabulary(), brief_options());
  const std::vector<SequenceFrame> frames = detect_sequence(sequence);
  const GroundTruth truth = GroundTruth::load(test::shared_data("rtabmap-samples/samples_GT.bmp"));
  const LoopReport report = make_loop_report(frames, sequence.params(), &truth);
  ASSERT_FALSE(report.loops.empty());
  EXPECT_TRUE(report.has_result);
  EXPECT_EQ(report.result.detections, report.loops.size());
  for (const ReportLoop& loop : report.loops) EXPECT_NE(loop.verdict, -1);
  test::TempDir dir;
  const std::string page = write_loop_report(dir.file("report"), report);
  EXPECT_TRUE(fs::exists(page));
}

}  // namespace
}  // namespace binbow::loop
