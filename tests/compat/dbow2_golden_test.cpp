// The DBoW2 layer against numbers produced by DBoW2 itself (dbow2_golden.txt).
#include <gtest/gtest.h>

#include <string>

#include "binbow/compat/DBoW2.h"
#include "compat/dbow2_golden.h"
#include "support/test_support.h"

namespace {

using binbow::test::source_path;

const dbow2_golden::Golden& golden() {
  static const dbow2_golden::Golden g =
      dbow2_golden::read(source_path("tests/compat/dbow2_golden.txt"));
  return g;
}

// The golden vocabulary: the bundled ORB vocabulary (see the golden file's header).
const OrbVocabulary& vocabulary() {
  static const OrbVocabulary voc(source_path("data/vocab/orb_default.bbw"));
  return voc;
}

void expect_bow_near(const DBoW2::BowVector& expected, const DBoW2::BowVector& actual,
                     const std::string& what) {
  ASSERT_EQ(expected.size(), actual.size()) << what;
  DBoW2::BowVector::const_iterator e = expected.begin(), a = actual.begin();
  for (; e != expected.end(); ++e, ++a) {
    ASSERT_EQ(e->first, a->first) << what;
    EXPECT_TRUE(dbow2_golden::close(e->second, a->second, 1e-9))
        << what << " word " << e->first << ": " << e->second << " vs " << a->second;
  }
}

TEST(Dbow2Golden, VocabularyParameters) {
  const OrbVocabulary& voc = vocabulary();
  EXPECT_EQ(golden().k, voc.getBranchingFactor());
  EXPECT_EQ(golden().L, voc.getDepthLevels());
  EXPECT_EQ(golden().weighting, voc.getWeightingType());
  EXPECT_EQ(golden().scoring, voc.getScoringType());
  EXPECT_EQ(golden().words, voc.size());
  EXPECT_FALSE(voc.empty());
}

TEST(Dbow2Golden, WordOfEachFeatureAndWeights) {
  const OrbVocabulary& voc = vocabulary();
  ASSERT_EQ(golden().images.size(), golden().feature_words.size());
  for (std::size_t i = 0; i < golden().images.size(); ++i) {
    ASSERT_EQ(golden().images[i].size(), golden().feature_words[i].size());
    for (std::size_t f = 0; f < golden().images[i].size(); ++f)
      EXPECT_EQ(golden().feature_words[i][f], voc.transform(golden().images[i][f]))
          << "image " << i << " feature " << f;
  }
  ASSERT_GT(golden().weights.size(), 100u);
  for (const auto& weight : golden().weights)
    EXPECT_EQ(weight.second, voc.getWordWeight(weight.first)) << "word " << weight.first;
}

TEST(Dbow2Golden, FeatureVectorsAtEveryLevelsup) {
  const OrbVocabulary& voc = vocabulary();
  std::size_t compared = 0, undefined_in_dbow2 = 0;
  for (int up = 0; up <= golden().L; ++up)
    for (std::size_t i = 0; i < golden().images.size(); ++i) {
      DBoW2::BowVector v;
      DBoW2::FeatureVector fv;
      voc.transform(golden().images[i], v, fv, up);
      std::vector<bool> seen(golden().images[i].size(), false);
      for (const auto& node : fv)
        for (unsigned int f : node.second) {
          ASSERT_LT(f, seen.size());
          seen[f] = true;
          // DBoW2's node, or binbow's (the leaf) where DBoW2 leaves it undefined.
          EXPECT_EQ(golden().nodes[up][i][f], node.first)
              << "levelsup " << up << " image " << i << " feature " << f;
          ++compared;
          if (golden().undefined[up][i][f]) ++undefined_in_dbow2;
        }
      for (std::size_t f = 0; f < seen.size(); ++f)
        EXPECT_TRUE(seen[f]) << "feature " << f << " of image " << i << " is missing";
      const auto expected = golden().feature_vectors.find(std::make_pair(up, static_cast<int>(i)));
      if (expected != golden().feature_vectors.end()) {
        EXPECT_TRUE(expected->second == fv) << "levelsup " << up << " image " << i;
      }
    }
  EXPECT_GT(compared, 3000u);
  EXPECT_GT(undefined_in_dbow2, 0u);  // the golden data do reach leaves above depth L
  EXPECT_GE(golden().feature_vectors.size(), 30u);
}

TEST(Dbow2Golden, LevelsupInTransformCountsFromTheRootAndGetParentNodeFromTheLeaf) {
  const OrbVocabulary& voc = vocabulary();
  std::size_t shallow = 0;
  for (const auto& parent : golden().parents) {
    for (std::size_t up = 0; up < parent.second.size(); ++up)
      EXPECT_EQ(parent.second[up], voc.getParentNode(parent.first, static_cast<int>(up)))
          << "word " << parent.first << " levelsup " << up;
    EXPECT_EQ(0u, parent.second.back());
  }
  // Image 6: descriptors of words shallower than L. At levelsup 1 transform
  // keeps the leaf itself (depth L - 1), getParentNode climbs one step.
  const std::vector<cv::Mat>& image = golden().images.back();
  DBoW2::BowVector v;
  DBoW2::FeatureVector fv;
  voc.transform(image, v, fv, 1);
  for (const auto& node : fv)
    for (unsigned int f : node.second) {
      const DBoW2::WordId word = voc.transform(image[f]);
      EXPECT_EQ(voc.getParentNode(word, 0), node.first);
      EXPECT_NE(voc.getParentNode(word, 1), node.first);
      ++shallow;
    }
  EXPECT_GT(shallow, 0u);
}

TEST(Dbow2Golden, BowVectorsUnderEveryWeightingAndScoring) {
  for (const auto& bow : golden().bows) {
    OrbVocabulary voc = vocabulary();
    voc.setWeightingType(dbow2_golden::weighting_named(bow.first.first.first));
    voc.setScoringType(dbow2_golden::scoring_named(bow.first.first.second));
    DBoW2::BowVector v;
    voc.transform(golden().images[bow.first.second], v);
    expect_bow_near(bow.second, v,
                    bow.first.first.first + " " + bow.first.first.second + " image " +
                        std::to_string(bow.first.second));
    // The same vector comes with the feature vector.
    DBoW2::BowVector v2;
    DBoW2::FeatureVector fv;
    voc.transform(golden().images[bow.first.second], v2, fv, 2);
    EXPECT_TRUE(v == v2);
  }
  EXPECT_EQ(4u * 6u + golden().images.size() - 1, golden().bows.size());
}

TEST(Dbow2Golden, PairwiseScores) {
  const std::size_t n = golden().images.size();
  for (const auto& scores : golden().scores) {
    OrbVocabulary voc = vocabulary();
    voc.setWeightingType(dbow2_golden::weighting_named(scores.first.first));
    voc.setScoringType(dbow2_golden::scoring_named(scores.first.second));
    std::vector<DBoW2::BowVector> bows(n);
    for (std::size_t i = 0; i < n; ++i) voc.transform(golden().images[i], bows[i]);
    ASSERT_EQ(n * n, scores.second.size());
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j)
        EXPECT_TRUE(
            dbow2_golden::close(scores.second[i * n + j], voc.score(bows[i], bows[j]), 1e-9))
            << scores.first.first << " " << scores.first.second << " (" << i << ", " << j
            << "): " << scores.second[i * n + j] << " vs " << voc.score(bows[i], bows[j]);
  }
  EXPECT_EQ(24u, golden().scores.size());
}

TEST(Dbow2Golden, StopWordsLeaveFeaturesOutOfBothVectors) {
  OrbVocabulary voc = vocabulary();
  EXPECT_EQ(golden().stopped_words, voc.stopWords(golden().stop_min_weight));
  DBoW2::BowVector v;
  DBoW2::FeatureVector fv;
  voc.transform(golden().images[golden().stop_image], v, fv, golden().stop_levelsup);
  expect_bow_near(golden().stop_bow, v, "after stopWords");
  EXPECT_TRUE(golden().stop_fv == fv);
  std::size_t kept = 0;
  for (const auto& node : fv) kept += node.second.size();
  EXPECT_LT(kept, golden().images[golden().stop_image].size());  // some features were left out
}

// Database scores come from binbow's index of single-precision values: they
// agree with DBoW2's to about 1e-7. L2_NORM's 1 - sqrt(1 - s) magnifies that
// near 1, so L2 scores are compared as s, the dot product.
bool same_score(const std::string& scoring, double expected, double actual) {
  if (scoring == "L2_NORM") {
    expected = 1 - (1 - expected) * (1 - expected);
    actual = 1 - (1 - actual) * (1 - actual);
  }
  return dbow2_golden::close(expected, actual, 1e-6);
}

// Entries of equal score may come in any order in DBoW2: compare ids as
// groups of equal scores.
void expect_same_results(const dbow2_golden::Query& expected, const DBoW2::QueryResults& actual,
                         const std::string& what) {
  ASSERT_EQ(expected.results.size(), actual.size()) << what;
  for (std::size_t r = 0; r < actual.size(); ++r) {
    EXPECT_TRUE(same_score(expected.scoring, expected.results[r].second, actual[r].Score))
        << what << " result " << r << ": " << expected.results[r].second << " vs "
        << actual[r].Score;
    if (expected.results[r].first == actual[r].Id) continue;
    bool tied = false;
    for (std::size_t t = 0; t < actual.size(); ++t)
      tied |= expected.results[t].first == actual[r].Id &&
              same_score(expected.scoring, expected.results[t].second, actual[r].Score);
    EXPECT_TRUE(tied) << what << " result " << r << ": entry " << expected.results[r].first
                      << " expected, " << actual[r].Id << " found";
  }
}

// DBoW2's queries do not read the direct index: the same golden results hold
// with and without one.
class Dbow2GoldenDatabase : public ::testing::TestWithParam<bool> {};

TEST_P(Dbow2GoldenDatabase, Queries) {
  const bool use_di = GetParam();
  std::map<std::string, OrbDatabase> databases;
  std::size_t limited_by_id = 0, filtered_by_common_words = 0;
  for (const dbow2_golden::Query& q : golden().queries) {
    if (!databases.count(q.scoring)) {
      OrbVocabulary voc = vocabulary();
      voc.setScoringType(dbow2_golden::scoring_named(q.scoring));
      OrbDatabase& db = databases[q.scoring];
      db.setVocabulary(voc, use_di, use_di ? 1 : 0);
      for (std::size_t i = 0; i < golden().images.size(); ++i)
        EXPECT_EQ(i, db.add(golden().images[i]));
    }
    DBoW2::QueryResults ret;
    databases[q.scoring].query(golden().images[q.image], ret, q.max_results, q.max_id);
    expect_same_results(q, ret,
                        q.scoring + " query " + std::to_string(q.image) + " max_results " +
                            std::to_string(q.max_results) + " max_id " + std::to_string(q.max_id));
    for (const DBoW2::Result& r : ret)
      EXPECT_TRUE(q.max_id == -1 || static_cast<int>(r.Id) < q.max_id) << r.Id;
    if (q.max_id != -1 && q.max_results == 3 && q.results.size() == 3) ++limited_by_id;
    if ((q.scoring == "CHI_SQUARE" || q.scoring == "BHATTACHARYYA") && q.image == 6)
      filtered_by_common_words += q.results.empty();
  }
  EXPECT_EQ(6u, databases.size());
  EXPECT_GT(limited_by_id, 0u);  // max_id restricts while max_results still fills up
  EXPECT_GT(filtered_by_common_words, 0u);
}

INSTANTIATE_TEST_SUITE_P(DirectIndex, Dbow2GoldenDatabase, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& param) {
                           return param.param ? "WithDirectIndex" : "WithoutDirectIndex";
                         });

}  // namespace
