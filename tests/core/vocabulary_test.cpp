#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <random>

#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "core/reference_tree.h"
#include "support/test_support.h"

namespace binbow {
namespace {

constexpr Scoring kAllScorings[] = {
    Scoring::kL1,        Scoring::kL2, Scoring::kChiSquare, Scoring::kKL, Scoring::kBhattacharyya,
    Scoring::kDotProduct};
constexpr Weighting kAllWeightings[] = {Weighting::kTfIdf, Weighting::kTf, Weighting::kIdf,
                                        Weighting::kBinary};

TEST(Vocabulary, FlatDescentEqualsExhaustiveDescentInPointerTree) {
  std::mt19937_64 rng(1);
  for (std::size_t code_size : {32, 64, 13}) {
    for (int trial = 0; trial < 4; ++trial) {
      const std::uint32_t k = 2 + static_cast<std::uint32_t>(rng() % 9);
      const std::uint32_t levels = 1 + static_cast<std::uint32_t>(rng() % 4);
      const VocabularyTree tree = test::random_tree(rng, code_size, k, levels);
      const Vocabulary v = Vocabulary::from_tree(tree);
      const test::ReferenceVocabulary ref(tree);
      ASSERT_EQ(v.word_count(), ref.word_count());
      const auto d = test::random_descriptors(300, code_size, rng);
      for (unsigned up = 0; up <= levels + 1; ++up) {
        std::vector<WordId> words(d.rows());
        std::vector<NodeId> nodes(d.rows());
        v.quantize(d, words.data(), nodes.data(), up);
        const std::uint32_t depth = up >= levels ? 0 : levels - up;
        for (std::size_t i = 0; i < d.rows(); ++i) {
          const auto [word, node] = ref.descend(d.row(i), depth);
          ASSERT_EQ(words[i], static_cast<WordId>(word)) << "descriptor " << i;
          ASSERT_EQ(nodes[i], node) << "descriptor " << i << " levels_up " << up;
          ASSERT_EQ(v.quantize(d.row(i)), words[i]);
        }
      }
    }
  }
}

TEST(Vocabulary, MeanQuantisationErrorIsTheMeanBitDistanceToEachDescriptorsLeaf) {
  std::mt19937_64 rng(4);
  const VocabularyTree tree = test::random_tree(rng, 32, 6, 3);
  const Vocabulary v = Vocabulary::from_tree(tree);
  const test::ReferenceVocabulary ref(tree);
  const auto d = test::random_descriptors(200, 32, rng);
  double total = 0;
  for (std::size_t i = 0; i < d.rows(); ++i)
    total += test::bit_distance(d.row(i),
                                v.node_descriptor(ref.descend(d.row(i), v.levels()).second), 32);
  EXPECT_NEAR(v.mean_quantisation_error(d), total / 200.0, 1e-9);
  EXPECT_EQ(v.mean_quantisation_error(DescriptorMatrix(0, 32)), 0.0);
  EXPECT_THROW(v.mean_quantisation_error(DescriptorMatrix(3, 64)), InvalidArgument);
}

TEST(Vocabulary, TransformEqualsDenseReferenceForEveryWeightingAndScoring) {
  std::mt19937_64 rng(2);
  for (Weighting weighting : kAllWeightings) {
    VocabularyTree tree = test::random_tree(rng, 32, 5, 3);
    tree.weighting = weighting;
    const Vocabulary base = Vocabulary::from_tree(tree);
    const test::ReferenceVocabulary ref(tree);
    for (Scoring scoring : kAllScorings) {
      const Vocabulary v = base.with_scoring(scoring);
      const auto a = test::random_descriptors(200, 32, rng);
      const auto b = test::random_descriptors(150, 32, rng);
      BowVector va, vb;
      v.transform(a, va);
      v.transform(b, vb);
      const auto ra = ref.transform(a, scoring);
      const auto rb = ref.transform(b, scoring);
      std::size_t nonzero = 0;
      for (double x : ra) nonzero += x != 0;
      ASSERT_EQ(va.size(), nonzero);
      for (const BowEntry& e : va) EXPECT_NEAR(e.value, ra[e.word], 1e-6);
      EXPECT_NEAR(v.score(va, vb), test::reference_score(ra, rb, scoring), 1e-5)
          << to_string(weighting) << " " << to_string(scoring);
    }
  }
}

TEST(Vocabulary, ScoresMatchHandComputedValues) {
  // v = (0.5, 0.5, 0), w = (0, 0.5, 0.5) over words 0, 1, 2.
  const BowVector v({{0, 0.5f}, {1, 0.5f}});
  const BowVector w({{1, 0.5f}, {2, 0.5f}});
  EXPECT_DOUBLE_EQ(score_bow(v, w, Scoring::kL1), 0.5);  // 1 − ½(0.5+0+0.5)
  EXPECT_DOUBLE_EQ(score_bow(v, w, Scoring::kDotProduct), 0.25);
  EXPECT_DOUBLE_EQ(score_bow(v, w, Scoring::kL2), 1.0 - std::sqrt(0.75));
  EXPECT_DOUBLE_EQ(score_bow(v, w, Scoring::kChiSquare), 0.5);  // 2 · 0.25/1
  EXPECT_DOUBLE_EQ(score_bow(v, w, Scoring::kBhattacharyya), 0.5);
  // KL: word 1 contributes 0.5·log(1); word 0, absent from w, 0.5·(log 0.5 − log ε).
  EXPECT_NEAR(score_bow(v, w, Scoring::kKL), 0.5 * (std::log(0.5) - std::log(DBL_EPSILON)), 1e-12);
  EXPECT_DOUBLE_EQ(score_bow(v, v, Scoring::kL1), 1.0);
  EXPECT_DOUBLE_EQ(score_bow(v, BowVector(), Scoring::kL1), 0.0);
}

TEST(Vocabulary, FeatureVectorGroupsFeaturesByNodeAndSkipsStopWords) {
  std::mt19937_64 rng(4);
  VocabularyTree tree = test::random_tree(rng, 32, 6, 4, 0.0);
  const Vocabulary v = Vocabulary::from_tree(tree);
  const auto d = test::random_descriptors(500, 32, rng);
  for (unsigned up = 0; up <= 4; ++up) {
    BowVector bow;
    FeatureVector fv;
    v.transform(d, bow, fv, up);
    std::vector<WordId> words(d.rows());
    std::vector<NodeId> nodes(d.rows());
    v.quantize(d, words.data(), nodes.data(), up);
    std::size_t expected = 0;
    for (std::size_t i = 0; i < d.rows(); ++i) {
      if (v.word_weight(words[i]) <= 0) {
        continue;
      }
      ++expected;
      const auto f = fv.features_of(nodes[i]);
      EXPECT_TRUE(std::find(f.begin(), f.end(), i) != f.end());
    }
    EXPECT_EQ(fv.feature_count(), expected);
    for (std::size_t n = 0; n + 1 < fv.size(); ++n) EXPECT_LT(fv.node(n), fv.node(n + 1));
    BowVector plain;
    v.transform(d, plain);
    EXPECT_EQ(plain, bow);
  }
}

TEST(Vocabulary, FromTreeRenumbersToDbow2OrderAndToTreeRoundTrips) {
  std::mt19937_64 rng(5);
  const VocabularyTree bfs = test::random_tree(rng, 32, 4, 3);
  const Vocabulary v = Vocabulary::from_tree(bfs);
  const VocabularyTree dfs = v.to_tree();
  // Already in DBoW2 order: identity.
  const Vocabulary again = Vocabulary::from_tree(dfs);
  EXPECT_EQ(again.serialize(), v.serialize());
  EXPECT_EQ(again.to_tree().parent, dfs.parent);
  for (std::size_t i = 1; i < dfs.node_count(); ++i) EXPECT_LT(dfs.parent[i], i);
}

TEST(Vocabulary, FromTreeRejectsBrokenTrees) {
  std::mt19937_64 rng(6);
  const VocabularyTree good = test::random_tree(rng, 32, 3, 3, 0.0);
  auto expect_rejected = [](VocabularyTree t, const char* what) {
    EXPECT_THROW(Vocabulary::from_tree(t), InvalidArgument) << what;
  };
  VocabularyTree t = good;
  t.parent[5] = static_cast<NodeId>(t.node_count() + 3);
  expect_rejected(t, "parent outside the tree");
  t = good;
  t.parent[4] = 5;  // 4 and 5 under the same parent at depth 1 → 5's child 4: may form a cycle
  t.parent[5] = 4;
  expect_rejected(t, "cycle");
  t = good;
  t.levels = 1;
  expect_rejected(t, "deeper than declared");
  t = good;
  t.branching = 1;
  expect_rejected(t, "too many children");
  t = good;
  t.descriptors.pop_back();
  expect_rejected(t, "descriptor size mismatch");
  t = good;
  t.code_size = 0;
  expect_rejected(t, "zero code size");
}

TEST(Vocabulary, TransformRejectsWrongDescriptorLengthAndEmptyVocabulary) {
  std::mt19937_64 rng(7);
  const Vocabulary v = Vocabulary::from_tree(test::random_tree(rng, 32, 3, 2));
  BowVector bow;
  const DescriptorMatrix wrong(3, 64);
  EXPECT_THROW(v.transform(wrong, bow), InvalidArgument);
  v.transform(DescriptorMatrix(0, 32), bow);
  EXPECT_TRUE(bow.empty());
  EXPECT_THROW(Vocabulary().transform(DescriptorMatrix(1, 32), bow), InvalidArgument);
}

TEST(Vocabulary, DescriptionAndChecksum) {
  std::mt19937_64 rng(8);
  const Vocabulary v = Vocabulary::from_tree(test::random_tree(rng, 32, 3, 2));
  EXPECT_NE(v.description().find("256-bit"), std::string::npos);
  EXPECT_EQ(v.checksum(), Vocabulary::from_tree(v.to_tree()).checksum());
  EXPECT_NE(v.checksum(), v.with_scoring(Scoring::kL2).checksum());
}

}  // namespace
}  // namespace binbow
