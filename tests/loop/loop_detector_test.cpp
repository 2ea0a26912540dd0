#include "binbow/loop/loop_detector.h"

#include <gtest/gtest.h>

#include <random>

#include "binbow/error.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

using vision::Features;

// A one-level vocabulary: every word's own descriptor quantises to it, so
// images can be written down as sets of words.
class WordImages {
 public:
  WordImages() {
    std::mt19937_64 rng(11);
    const DescriptorMatrix training = test::random_descriptors(4000, 32, rng);
    std::vector<DescriptorView> images;
    for (std::size_t i = 0; i < 40; ++i) images.push_back(training.view().slice(i * 100, 100));
    BuildOptions options;
    options.branching = 200;
    options.levels = 1;
    vocabulary_ = Vocabulary::build(images, options);
    leaves_ = vocabulary_.word_nodes();
  }

  const Vocabulary& vocabulary() const { return vocabulary_; }

  Features image(const std::vector<WordId>& words) const {
    Features f;
    f.descriptors = DescriptorMatrix(32);
    for (WordId w : words) {
      f.descriptors.append(vocabulary_.node_descriptor(leaves_[w]));
      f.keypoints.push_back({float(w), float(w), 10, -1, 1, 0});
    }
    return f;
  }

  // Place i: ten words of its own and five of place i + 1, so consecutive
  // images share words (as consecutive frames of a video do).
  Features place(int i) const {
    std::vector<WordId> words;
    for (int w = 0; w < 10; ++w) words.push_back(WordId(10 * i + w));
    for (int w = 0; w < 5; ++w) words.push_back(WordId(10 * (i + 1) + w));
    return image(words);
  }

 private:
  Vocabulary vocabulary_;
  std::vector<NodeId> leaves_;
};

LoopDetectorParams small_params() {
  LoopDetectorParams p;
  p.dislocal = 3;
  p.geometric_check = GeometricCheck::kNone;
  return p;
}

TEST(LoopDetector, NormalisationSkipIslandsTemporalConsistencyThenLoop) {
  const WordImages words;
  ASSERT_EQ(words.vocabulary().word_count(), 200u);
  LoopDetector detector(words.vocabulary(), small_params());
  // Walk places 0..9, then walk them again.
  for (int i = 0; i < 10; ++i) {
    const LoopResult r = detector.process(words.place(i));
    EXPECT_EQ(r.query, EntryId(i));
    EXPECT_FALSE(r.detection()) << i;
    // Places never repeat on the first walk: anything older than dislocal shares no word.
    if (i <= 3) {
      EXPECT_EQ(r.status, LoopStatus::kNoDatabaseResults) << i;
    }
  }
  // The revisit starts with a jump: image 10 shares nothing with image 9, so
  // η cannot be normalised and the frame is skipped.
  LoopResult r = detector.process(words.place(0));
  EXPECT_EQ(r.status, LoopStatus::kLowNormalisationScore);
  EXPECT_LT(r.normalisation_score, 0.005);
  EXPECT_TRUE(r.has_candidate);
  EXPECT_EQ(r.match, 0u);
  // Then k = 3 consistent queries are needed before the fourth is a loop.
  for (int i = 1; i <= 3; ++i) {
    r = detector.process(words.place(i));
    EXPECT_EQ(r.status, LoopStatus::kNoTemporalConsistency) << i;
    EXPECT_EQ(r.consistent_queries, i);
    EXPECT_EQ(r.match, EntryId(i));
    EXPECT_GT(r.normalised_score, 1.0);  // the old image beats the previous frame
    EXPECT_LE(r.island_first, EntryId(i));
    EXPECT_GE(r.island_last, EntryId(i));
    EXPECT_GE(r.island_score, r.normalised_score);
  }
  for (int i = 4; i < 7; ++i) {
    r = detector.process(words.place(i));
    EXPECT_EQ(r.status, LoopStatus::kLoopDetected) << i;
    EXPECT_EQ(r.match, EntryId(i));
    EXPECT_NEAR(r.score, r.normalised_score * r.normalisation_score, 1e-9);
  }
  EXPECT_EQ(detector.size(), 17u);
}

// A featureless frame (blur, darkness) in the middle of a revisit: with
// skip_featureless_frames the next frame is normalised by the frame before
// it and the temporal chain goes on; DLoopDetector's rule skips the next
// frame and restarts the chain.
TEST(LoopDetector, FeaturelessFrameDoesNotBreakTheChain) {
  const WordImages words;
  for (const bool skip : {true, false}) {
    SCOPED_TRACE(skip ? "skip featureless frames" : "DLoopDetector's rule");
    LoopDetectorParams p = small_params();
    p.skip_featureless_frames = skip;
    LoopDetector detector(words.vocabulary(), p);
    for (int i = 0; i < 10; ++i) detector.process(words.place(i));
    for (int i = 0; i <= 3; ++i) detector.process(words.place(i));  // chain of 3 after the jump
    EXPECT_EQ(detector.process(Features{}).status, LoopStatus::kNoDatabaseResults);
    const LoopResult after = detector.process(words.place(4));
    const LoopResult next = detector.process(words.place(5));
    if (skip) {
      EXPECT_EQ(after.status, LoopStatus::kLoopDetected);
      EXPECT_GT(after.normalisation_score, 0.005);  // s(place 4, place 3)
      EXPECT_EQ(after.consistent_queries, 4);
      EXPECT_EQ(next.status, LoopStatus::kLoopDetected);
    } else {
      EXPECT_EQ(after.status, LoopStatus::kLowNormalisationScore);
      EXPECT_EQ(next.status, LoopStatus::kNoTemporalConsistency);
      EXPECT_EQ(next.consistent_queries, 1);
    }
  }
}

TEST(LoopDetector, AlphaAndIslandLengthFilterCandidates) {
  const WordImages words;
  LoopDetectorParams p = small_params();
  p.alpha = 100;  // no η can reach it
  LoopDetector strict(words.vocabulary(), p);
  for (int i = 0; i < 10; ++i) strict.process(words.place(i));
  strict.process(words.place(0));
  EXPECT_EQ(strict.process(words.place(1)).status, LoopStatus::kLowScores);

  p = small_params();
  p.min_matches_per_island = 10;  // longer than any island here
  LoopDetector picky(words.vocabulary(), p);
  for (int i = 0; i < 10; ++i) picky.process(words.place(i));
  picky.process(words.place(0));
  EXPECT_EQ(picky.process(words.place(1)).status, LoopStatus::kNoIslands);
}

TEST(LoopDetector, WithoutNormalisationRawScoresAreCompared) {
  const WordImages words;
  LoopDetectorParams p = small_params();
  p.use_normalised_score = false;
  p.alpha = 0.1;
  p.k = 0;
  LoopDetector detector(words.vocabulary(), p);
  for (int i = 0; i < 10; ++i) detector.process(words.place(i));
  const LoopResult r = detector.process(words.place(0));  // no skip without η
  EXPECT_EQ(r.status, LoopStatus::kLoopDetected);
  EXPECT_EQ(r.match, 0u);
  EXPECT_DOUBLE_EQ(r.normalised_score, r.score);
}

TEST(LoopDetector, EmptyImagesAndBadInput) {
  const WordImages words;
  LoopDetector detector(words.vocabulary(), LoopDetectorParams{});
  for (int i = 0; i < 30; ++i) {
    const LoopResult r = detector.process(Features{});
    EXPECT_EQ(r.status, LoopStatus::kNoDatabaseResults);
  }
  Features mismatch = words.place(1);
  mismatch.keypoints.pop_back();
  EXPECT_THROW(detector.process(mismatch), InvalidArgument);
  Features wide;
  wide.descriptors = DescriptorMatrix(2, 64);
  wide.keypoints.resize(2);
  EXPECT_THROW(detector.process(wide), InvalidArgument);
  LoopDetectorParams bad;
  bad.k = -1;
  EXPECT_THROW(LoopDetector(words.vocabulary(), bad), InvalidArgument);
  EXPECT_THROW(LoopDetector(Vocabulary(), LoopDetectorParams{}), InvalidArgument);
  detector.clear();
  EXPECT_EQ(detector.size(), 0u);
  EXPECT_EQ(detector.process(words.place(0)).query, 0u);
}

TEST(LoopDetector, KeepsFeaturesForVerification) {
  const WordImages words;
  LoopDetector detector(words.vocabulary(), LoopDetectorParams{});
  const Features f = words.place(2);
  detector.process(words.place(1));
  detector.process(f);
  ASSERT_EQ(detector.keypoints(1).size(), f.keypoints.size());
  EXPECT_EQ(detector.keypoints(1)[3].x, f.keypoints[3].x);
  EXPECT_EQ(detector.descriptors(1).rows, f.descriptors.rows());
  EXPECT_EQ(hamming_distance(detector.descriptors(1).row(4), f.descriptors.row(4), 32), 0u);
  EXPECT_THROW(detector.keypoints(2), InvalidArgument);
}

}  // namespace
}  // namespace binbow::loop

namespace binbow::loop {
namespace {

// Places as in WordImages, but of raw random descriptors (about 128 bits
// apart, so each becomes a word of its own) that an online vocabulary must
// learn; a revisit flips a few bits of each.
class RandomPlaces {
 public:
  RandomPlaces() {
    std::mt19937_64 rng(3);
    descriptors_ = test::random_descriptors(10 * 41, 32, rng);
  }
  Features place(int i, std::mt19937_64* noise = nullptr) const {
    Features f;
    f.descriptors = DescriptorMatrix(32);
    std::vector<std::size_t> rows;
    for (int w = 0; w < 10; ++w) rows.push_back(10 * i + w);
    for (int w = 0; w < 5; ++w) rows.push_back(10 * (i + 1) + w);
    for (std::size_t row : rows) {
      std::vector<std::uint8_t> d(descriptors_.row(row), descriptors_.row(row) + 32);
      if (noise != nullptr)
        for (int flip = 0; flip < 6; ++flip)
          d[(*noise)() % 32] ^= std::uint8_t(1u << ((*noise)() % 8));
      f.descriptors.append(d.data());
      f.keypoints.push_back({float(row), float(row), 10, -1, 1, 0});
    }
    return f;
  }

 private:
  DescriptorMatrix descriptors_;
};

std::vector<LoopResult> run_twice_around(LoopDetector& detector, const RandomPlaces& places) {
  std::mt19937_64 noise(9);
  std::vector<LoopResult> results;
  for (int i = 0; i < 40; ++i) results.push_back(detector.process(places.place(i)));
  for (int i = 0; i < 40; ++i) results.push_back(detector.process(places.place(i, &noise)));
  return results;
}

TEST(OnlineLoopDetector, LearnsThePlacesOnTheFirstPassAndRecognisesThemOnTheSecond) {
  const RandomPlaces places;
  LoopDetector detector = LoopDetector::online(32, {}, small_params());
  ASSERT_NE(detector.online_vocabulary(), nullptr);
  const std::vector<LoopResult> results = run_twice_around(detector, places);
  for (int i = 0; i < 40; ++i) EXPECT_FALSE(results[i].detection()) << "first pass, frame " << i;
  int loops = 0;
  for (int i = 40; i < 80; ++i) {
    if (!results[i].detection()) continue;
    ++loops;
    EXPECT_NEAR(double(results[i].match), double(i - 40), 1.0) << "frame " << i;
  }
  // All but the first k = 3 revisits, which build temporal consistency.
  EXPECT_GE(loops, 36);

  // Same input, same output.
  LoopDetector again = LoopDetector::online(32, {}, small_params());
  const std::vector<LoopResult> repeated = run_twice_around(again, places);
  for (std::size_t i = 0; i < results.size(); ++i) {
    EXPECT_EQ(repeated[i].status, results[i].status) << i;
    EXPECT_EQ(repeated[i].match, results[i].match) << i;
    EXPECT_EQ(repeated[i].score, results[i].score) << i;
  }

  detector.clear();
  EXPECT_EQ(detector.size(), 0u);
  EXPECT_EQ(detector.online_vocabulary()->word_count(), 0u);
  // Cleared, it starts over with the same vocabulary options: the same results again.
  const std::vector<LoopResult> after_clear = run_twice_around(detector, places);
  for (std::size_t i = 0; i < results.size(); ++i) {
    EXPECT_EQ(after_clear[i].status, results[i].status) << i;
    EXPECT_EQ(after_clear[i].match, results[i].match) << i;
  }
}

TEST(OnlineLoopDetector, DirectIndexPairsFeaturesOfTheSameWord) {
  const RandomPlaces places;
  LoopDetectorParams params = small_params();
  params.geometric_check = GeometricCheck::kDirectIndex;
  LoopDetector detector = LoopDetector::online(32, {}, params);
  const Features first = places.place(0);
  detector.process(first);
  const FeatureVector nodes = detector.database().feature_vector(0);
  OnlineImageWords expected = OnlineVocabulary(32).add_image(first.descriptors.view());
  ASSERT_EQ(nodes.feature_count(), first.descriptors.rows());
  for (std::size_t i = 0; i < nodes.size(); ++i)
    for (std::uint32_t feature : nodes.features(i))
      EXPECT_EQ(nodes.node(i), expected.words[feature]);
  EXPECT_THROW(LoopDetector::online(0, {}, params), InvalidArgument);
  Features wide;
  wide.descriptors = DescriptorMatrix(2, 64);
  wide.keypoints.resize(2);
  EXPECT_THROW(detector.process(wide), InvalidArgument);
}

}  // namespace
}  // namespace binbow::loop
