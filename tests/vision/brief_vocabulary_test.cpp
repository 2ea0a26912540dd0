// Our BRIEF with DBoW2 BRIEF vocabularies.
//
// Bit order: DBoW2 stores a BRIEF word as bitset::to_string() (bit 255
// first). The first test writes descriptors computed by the reference
// definition (DVision::BRIEF) in exactly that form into a DBoW2 YAML file,
// reads it with binbow's loader and checks that the words are, byte for byte,
// the descriptors our extractor computes — extractor and loader agree.
//
// The real vocabulary brief_lite.voc.gz cannot prove the bit order by
// itself: it fits these images poorly, and measured on rtabmap-samples our
// descriptors lie 106.9 bits from their word (the reference implementation:
// ~106), but uniformly random descriptors lie 107.8 bits away and the same
// descriptors with reversed bit order 107.0. What it does show is that, with
// our extractor, it recognises places as the reference does. It does not
// single out the DBoW2 demo's staircase (image1-image3 scores 0.044 with 300
// features, image2-image3 0.067), although the descriptors themselves do:
// see Matching.SameStaircaseHasFarMoreCloseMatchesThanDifferentPlaces.
#include <bitset>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "binbow/bow_vector.h"
#include "binbow/formats.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"
#include "vision/brief_pattern.h"

namespace binbow::vision {
namespace {

using test::shared_data;

TEST(BriefWithDbow2, ReferenceDescriptorsWrittenByDbow2LoadAsOurBytes) {
  const cv::Mat image = read_grey_image(shared_data("dbow2-demo-images/image1.png"));
  const Features features = make_brief_extractor()->extract(image);
  ASSERT_EQ(features.keypoints.size(), 300u);

  // DVision::BRIEF for the first ten keypoints, as DBoW2 would save them.
  cv::Mat smoothed;
  cv::GaussianBlur(image, smoothed, cv::Size(9, 9), 2, 2);
  const BriefPattern& pattern = default_brief_pattern();
  constexpr int kWords = 10;
  std::string yaml =
      "%YAML:1.0\n---\nvocabulary:\n   k: 10\n   L: 1\n   scoringType: 0\n   weightingType: 0\n"
      "   nodes:\n";
  for (int k = 0; k < kWords; ++k) {
    const int x = static_cast<int>(features.keypoints[k].x);
    const int y = static_cast<int>(features.keypoints[k].y);
    std::bitset<256> bits;
    for (std::size_t i = 0; i < 256; ++i) {
      bits[i] = smoothed.at<std::uint8_t>(y + pattern.y1[i], x + pattern.x1[i]) <
                smoothed.at<std::uint8_t>(y + pattern.y2[i], x + pattern.x2[i]);
    }
    yaml += "      - { nodeId:" + std::to_string(k + 1) + ", parentId:0, weight:1.,\n" +
            "          descriptor:\"" + bits.to_string() + "\" }\n";
  }
  yaml += "   words:\n";
  for (int k = 0; k < kWords; ++k) {
    yaml += "      - { wordId:" + std::to_string(k) + ", nodeId:" + std::to_string(k + 1) + " }\n";
  }
  test::TempDir dir;
  std::ofstream(dir.file("words.yml")) << yaml;

  const Vocabulary vocabulary = load_vocabulary(dir.file("words.yml"));
  ASSERT_EQ(vocabulary.word_count(), static_cast<std::size_t>(kWords));
  ASSERT_EQ(vocabulary.code_size(), 32u);
  const std::vector<NodeId> leaves = vocabulary.word_nodes();
  for (int k = 0; k < kWords; ++k) {
    const std::uint8_t* word = vocabulary.node_descriptor(leaves[k]);
    EXPECT_TRUE(std::equal(word, word + 32, features.descriptors.row(k))) << "word " << k;
    EXPECT_EQ(vocabulary.quantize(features.descriptors.row(k)), static_cast<WordId>(k));
  }
}

class BriefLiteVocabulary : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    vocabulary_ =
        new Vocabulary(load_vocabulary(shared_data("vins-lite-brief-vocab/brief_lite.voc.gz")));
  }
  static void TearDownTestSuite() {
    delete vocabulary_;
    vocabulary_ = nullptr;
  }
  static BowVector bow(const DescriptorMatrix& descriptors) {
    BowVector vector;
    vocabulary_->transform(descriptors, vector);
    return vector;
  }

  static Vocabulary* vocabulary_;
};

Vocabulary* BriefLiteVocabulary::vocabulary_ = nullptr;

std::set<std::pair<int, int>> rtabmap_ground_truth() {
  std::ifstream file(shared_data("rtabmap-samples/samples_GT_pairs.txt"));
  std::set<std::pair<int, int>> pairs;
  std::string line;
  while (std::getline(file, line)) {
    if (line.empty() || line[0] == '#') continue;
    int query = 0, match = 0;
    if (std::sscanf(line.c_str(), "%d %d", &query, &match) == 2) pairs.insert({query, match});
  }
  return pairs;
}

// Frames of the same place score higher on average than frames of different
// places, and the best-scoring earlier frame is often a true match (the
// reference's recall without geometric check: 0.55-0.59 at precision 0.5).
// Random descriptors would give a ratio of ~1 and ~5 right answers of 44
// (each query has ~5 true matches among ~50 earlier frames).
TEST_F(BriefLiteVocabulary, SamePlaceFramesScoreHigherThanDifferentPlaces) {
  const std::set<std::pair<int, int>> same_place = rtabmap_ground_truth();
  ASSERT_GT(same_place.size(), 200u);
  const auto extractor = make_brief_extractor();
  std::vector<BowVector> vectors(85);
  for (int frame = 1; frame <= 84; ++frame) {
    const std::string path = "rtabmap-samples/samples/" + std::to_string(frame) + ".jpg";
    vectors[frame] = bow(extractor->extract(read_grey_image(shared_data(path))).descriptors);
  }
  double same_total = 0, different_total = 0;
  std::size_t same_count = 0, different_count = 0, queries = 0, right_first = 0;
  for (int query = 41; query <= 84; ++query) {
    int best = 0;
    double best_score = -1;
    bool revisits = false;
    for (int match = 1; match < query - 10; ++match) {
      const double score = vocabulary_->score(vectors[query], vectors[match]);
      if (score > best_score) {
        best_score = score;
        best = match;
      }
      if (same_place.count({query, match}) != 0) {
        same_total += score;
        ++same_count;
        revisits = true;
        continue;
      }
      // Different places: at least 6 frames from every true match.
      bool near_a_match = false;
      for (int d = -5; d <= 5; ++d) near_a_match |= same_place.count({query, match + d}) != 0;
      if (!near_a_match) {
        different_total += score;
        ++different_count;
      }
    }
    if (revisits) {
      ++queries;
      right_first += same_place.count({query, best});
    }
  }
  ASSERT_GT(same_count, 100u);
  ASSERT_GT(different_count, 500u);
  const double same_mean = same_total / static_cast<double>(same_count);
  const double different_mean = different_total / static_cast<double>(different_count);
  std::printf(
      "mean score, same place %.4f (%zu pairs), different places %.4f (%zu pairs); "
      "best match right for %zu of %zu queries\n",
      same_mean, same_count, different_mean, different_count, right_first, queries);
  // Measured 2026-11-22: 0.0489 against 0.0340; 24 of 44.
  EXPECT_GT(same_mean, 1.25 * different_mean);
  EXPECT_GE(right_first, 18u);
}

}  // namespace
}  // namespace binbow::vision
