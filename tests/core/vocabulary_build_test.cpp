#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "binbow/descriptors.h"
#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

// Splits `rows` into `images` consecutive views of (almost) equal size.
std::vector<DescriptorView> split(const DescriptorMatrix& rows, std::size_t images) {
  std::vector<DescriptorView> views;
  for (std::size_t i = 0; i < images; ++i) {
    const std::size_t begin = rows.rows() * i / images, end = rows.rows() * (i + 1) / images;
    views.push_back(rows.view().slice(begin, end - begin));
  }
  return views;
}

BuildOptions options_for(std::uint32_t k, std::uint32_t levels, unsigned threads = 1) {
  BuildOptions options;
  options.branching = k;
  options.levels = levels;
  options.threads = threads;
  options.seed = 12345;
  return options;
}

std::uint32_t depth_of(const std::vector<NodeId>& parent, NodeId node) {
  std::uint32_t depth = 0;
  for (; node != 0; node = parent[node]) ++depth;
  return depth;
}

TEST(VocabularyBuild, RejectsBadOptionsAndInput) {
  std::mt19937_64 rng(1);
  const DescriptorMatrix rows = test::random_descriptors(100, 32, rng);
  const DescriptorMatrix other = test::random_descriptors(10, 64, rng);
  const std::vector<DescriptorView> images = split(rows, 4);
  EXPECT_THROW(Vocabulary::build({}, options_for(10, 3)), InvalidArgument);
  EXPECT_THROW(Vocabulary::build({DescriptorView{nullptr, 0, 32}}, options_for(10, 3)),
               InvalidArgument);
  EXPECT_THROW(Vocabulary::build({rows.view(), other.view()}, options_for(10, 3)), InvalidArgument);
  EXPECT_THROW(Vocabulary::build(images, options_for(1, 3)), InvalidArgument);
  EXPECT_THROW(Vocabulary::build(images, options_for(256, 3)), InvalidArgument);
  EXPECT_THROW(Vocabulary::build(images, options_for(10, 0)), InvalidArgument);
  EXPECT_THROW(Vocabulary::build(images, options_for(10, 17)), InvalidArgument);
  BuildOptions bad_fraction = options_for(10, 3);
  bad_fraction.stop_word_fraction = -0.5;
  EXPECT_THROW(Vocabulary::build(images, bad_fraction), InvalidArgument);
  try {
    Vocabulary::build({rows.view(), other.view()}, options_for(10, 3));
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("mixed descriptor sizes"), std::string::npos) << e.what();
  }
  // The extremes of the accepted ranges work.
  EXPECT_NO_THROW(Vocabulary::build(images, options_for(2, 16)));
  EXPECT_NO_THROW(Vocabulary::build(images, options_for(255, 1)));
}

TEST(VocabularyBuild, TreeHasTheRequestedShapeAndDbow2Order) {
  std::mt19937_64 rng(2);
  const DescriptorMatrix rows = test::clustered_descriptors(4000, 32, 40, 0.1, rng);
  const std::uint32_t k = 5, levels = 4;
  const Vocabulary vocabulary = Vocabulary::build(split(rows, 20), options_for(k, levels));
  EXPECT_EQ(vocabulary.branching(), k);
  EXPECT_EQ(vocabulary.levels(), levels);
  EXPECT_EQ(vocabulary.code_size(), 32u);
  const VocabularyTree tree = vocabulary.to_tree();
  ASSERT_EQ(tree.node_count(), vocabulary.node_count());

  std::size_t leaves = 0;
  std::vector<std::vector<NodeId>> children(tree.node_count());
  for (NodeId node = 1; node < tree.node_count(); ++node)
    children[tree.parent[node]].push_back(node);
  for (NodeId node = 0; node < tree.node_count(); ++node) {
    EXPECT_LE(children[node].size(), k);
    EXPECT_LE(depth_of(tree.parent, node), levels);
    if (children[node].empty()) {
      ++leaves;
      EXPECT_TRUE(vocabulary.is_leaf(node));
      continue;
    }
    // Children are distinct descriptors.
    std::set<std::string> distinct;
    for (const NodeId child : children[node]) {
      distinct.insert(
          std::string(reinterpret_cast<const char*>(vocabulary.node_descriptor(child)), 32));
    }
    EXPECT_EQ(distinct.size(), children[node].size()) << "node " << node;
  }
  EXPECT_EQ(vocabulary.word_count(), leaves);
  EXPECT_GT(leaves, 100u);
  EXPECT_LE(leaves, 625u);  // k^L

  // DBoW2 order: a node's children get consecutive ids, then each child's
  // subtree is numbered in turn. Renumbering that way must be the identity.
  std::vector<NodeId> expected(tree.node_count(), 0);
  NodeId next = 1;
  std::function<void(NodeId)> number = [&](NodeId node) {
    for (const NodeId child : children[node]) expected[child] = next++;
    for (const NodeId child : children[node]) number(child);
  };
  number(0);
  for (NodeId node = 0; node < tree.node_count(); ++node) ASSERT_EQ(expected[node], node);
  // Words are the leaves in node order.
  const std::vector<NodeId> word_nodes = vocabulary.word_nodes();
  for (std::size_t w = 1; w < word_nodes.size(); ++w) EXPECT_LT(word_nodes[w - 1], word_nodes[w]);
}

TEST(VocabularyBuild, SameSeedGivesIdenticalBytesForAnyThreadCount) {
  std::mt19937_64 rng(3);
  // More than two chunks' worth of rows at the root, so threads split nodes
  // as well as sharing them out.
  const DescriptorMatrix rows = test::clustered_descriptors(34000, 32, 200, 0.15, rng);
  const std::vector<DescriptorView> images = split(rows, 50);
  const std::vector<std::uint8_t> one = Vocabulary::build(images, options_for(8, 2, 1)).serialize();
  EXPECT_EQ(one, Vocabulary::build(images, options_for(8, 2, 2)).serialize());
  BuildOptions other_seed = options_for(8, 2, 2);
  other_seed.seed = 54321;
  EXPECT_NE(one, Vocabulary::build(images, other_seed).serialize());
}

TEST(VocabularyBuild, OneLevelQuantisesEveryTrainingRowToItsNearestWord) {
  std::mt19937_64 rng(4);
  const DescriptorMatrix rows = test::clustered_descriptors(3000, 32, 8, 0.1, rng);
  BuildOptions options = options_for(8, 1);
  options.max_iterations = 1000;
  options.weighting = Weighting::kTf;  // every image has every word: IDF would weigh them 0
  const Vocabulary vocabulary = Vocabulary::build(split(rows, 10), options);
  ASSERT_EQ(vocabulary.word_count(), 8u);
  const std::vector<NodeId> word_nodes = vocabulary.word_nodes();
  std::vector<WordId> words(rows.rows());
  vocabulary.quantize(rows.view(), words.data());
  std::vector<std::size_t> members(8, 0);
  for (std::size_t i = 0; i < rows.rows(); ++i) {
    WordId best = 0;
    std::uint32_t best_distance = 1000;
    for (WordId w = 0; w < 8; ++w) {
      const std::uint32_t d =
          hamming_distance(rows.row(i), vocabulary.node_descriptor(word_nodes[w]), 32);
      if (d < best_distance) {
        best_distance = d;
        best = w;
      }
    }
    ASSERT_EQ(words[i], best) << "row " << i;
    ++members[best];
  }
  for (const std::size_t count : members) EXPECT_GT(count, 0u);
}

// Four far-apart descriptors A, B, C, D; images {A, B}, {A, C}, {A, A, D}, {B}.
struct TinyCase {
  DescriptorMatrix values{4, 32};
  std::vector<DescriptorMatrix> images;
  std::vector<DescriptorView> views;

  TinyCase() {
    for (int v = 0; v < 4; ++v) {
      for (int byte = 0; byte < 32; ++byte) {
        values.row(v)[byte] = static_cast<std::uint8_t>(byte % 4 == v ? 0xff : 0x00);
      }
    }
    for (const std::vector<int>& image :
         std::vector<std::vector<int>>{{0, 1}, {0, 2}, {0, 0, 3}, {1}}) {
      DescriptorMatrix m(32);
      for (const int v : image) m.append(values.row(v));
      images.push_back(std::move(m));
    }
    for (const DescriptorMatrix& m : images) views.push_back(m.view());
  }

  float weight_of(const Vocabulary& vocabulary, int value) const {
    return vocabulary.word_weight(vocabulary.quantize(values.row(value)));
  }
};

TEST(VocabularyBuild, IdfWeightsMatchAHandComputation) {
  const TinyCase tiny;
  for (const Weighting weighting : {Weighting::kTfIdf, Weighting::kIdf}) {
    BuildOptions options = options_for(4, 2);
    options.weighting = weighting;
    const Vocabulary vocabulary = Vocabulary::build(tiny.views, options);
    ASSERT_EQ(vocabulary.word_count(), 4u);
    EXPECT_EQ(vocabulary.weighting(), weighting);
    // N = 4 images; A in 3, B in 2, C in 1, D in 1.
    EXPECT_FLOAT_EQ(tiny.weight_of(vocabulary, 0), static_cast<float>(std::log(4.0 / 3.0)));
    EXPECT_FLOAT_EQ(tiny.weight_of(vocabulary, 1), static_cast<float>(std::log(2.0)));
    EXPECT_FLOAT_EQ(tiny.weight_of(vocabulary, 2), static_cast<float>(std::log(4.0)));
    EXPECT_FLOAT_EQ(tiny.weight_of(vocabulary, 3), static_cast<float>(std::log(4.0)));
  }
}

TEST(VocabularyBuild, IdfWeightsMatchDocumentFrequenciesOfTheFinishedTree) {
  std::mt19937_64 rng(6);
  const DescriptorMatrix rows = test::clustered_descriptors(3000, 32, 30, 0.2, rng);
  const std::vector<DescriptorView> images = split(rows, 37);
  const Vocabulary vocabulary = Vocabulary::build(images, options_for(4, 4));
  // N_i by quantising every training image with the finished tree.
  std::vector<std::size_t> image_count(vocabulary.word_count(), 0);
  for (const DescriptorView& image : images) {
    std::vector<WordId> words(image.rows);
    vocabulary.quantize(image, words.data());
    const std::set<WordId> present(words.begin(), words.end());
    for (const WordId word : present) ++image_count[word];
  }
  std::size_t unused = 0;
  for (WordId word = 0; word < vocabulary.word_count(); ++word) {
    if (image_count[word] == 0) {
      // A training row can descend to another leaf than the cluster it built.
      ++unused;
      EXPECT_EQ(vocabulary.word_weight(word), 0.0f) << "word " << word;
    } else {
      EXPECT_FLOAT_EQ(vocabulary.word_weight(word),
                      static_cast<float>(std::log(37.0 / image_count[word])))
          << "word " << word;
    }
  }
  EXPECT_LT(unused, vocabulary.word_count() / 10);
}

TEST(VocabularyBuild, TfAndBinaryWeightsAreOne) {
  const TinyCase tiny;
  for (const Weighting weighting : {Weighting::kTf, Weighting::kBinary}) {
    BuildOptions options = options_for(4, 2);
    options.weighting = weighting;
    options.scoring = Scoring::kL2;
    const Vocabulary vocabulary = Vocabulary::build(tiny.views, options);
    EXPECT_EQ(vocabulary.scoring(), Scoring::kL2);
    for (WordId w = 0; w < vocabulary.word_count(); ++w) EXPECT_EQ(vocabulary.word_weight(w), 1.0f);
  }
}

TEST(VocabularyBuild, StopWordsGetZeroWeight) {
  const TinyCase tiny;
  BuildOptions options = options_for(4, 2);
  options.stop_word_fraction = 0.5;  // words in more than 2 of the 4 images
  options.weighting = Weighting::kTf;
  const Vocabulary tf = Vocabulary::build(tiny.views, options);
  EXPECT_EQ(tiny.weight_of(tf, 0), 0.0f);
  EXPECT_EQ(tiny.weight_of(tf, 1), 1.0f);
  EXPECT_EQ(tiny.weight_of(tf, 2), 1.0f);
  options.weighting = Weighting::kTfIdf;
  options.stop_word_fraction = 0.25;  // more than one image: A and B
  const Vocabulary tf_idf = Vocabulary::build(tiny.views, options);
  EXPECT_EQ(tiny.weight_of(tf_idf, 0), 0.0f);
  EXPECT_EQ(tiny.weight_of(tf_idf, 1), 0.0f);
  EXPECT_FLOAT_EQ(tiny.weight_of(tf_idf, 2), static_cast<float>(std::log(4.0)));
}

// A vocabulary whose words all weigh 0 makes every BoW vector empty: an
// error that says why, not a useless file.
TEST(VocabularyBuild, RejectsTrainingSetsThatGiveEveryWordWeightZero) {
  std::mt19937_64 rng(8);
  const DescriptorMatrix rows = test::random_descriptors(200, 32, rng);
  const auto expect_error = [](const std::vector<DescriptorView>& images,
                               const BuildOptions& options, const std::string& expected) {
    try {
      Vocabulary::build(images, options);
      ADD_FAILURE() << "no error; expected: " << expected;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  const std::string why = "needs at least two training images that differ";
  for (const Weighting weighting : {Weighting::kTfIdf, Weighting::kIdf}) {
    BuildOptions options = options_for(4, 2);
    options.weighting = weighting;
    expect_error({rows.view()}, options, why);
    expect_error({rows.view(), rows.view()}, options, why);  // every word in both images
  }
  BuildOptions every_word_stopped = options_for(4, 2);
  every_word_stopped.weighting = Weighting::kTf;
  every_word_stopped.stop_word_fraction = 0;
  expect_error(split(rows, 4), every_word_stopped, "every word is a stop word");
  // One image is fine when the weights do not depend on the image count.
  BuildOptions tf = options_for(4, 2);
  tf.weighting = Weighting::kTf;
  EXPECT_NO_THROW(Vocabulary::build({rows.view()}, tf));
}

TEST(VocabularyBuild, IdenticalDescriptorsMakeOneWord) {
  std::vector<std::uint8_t> same(50 * 32, 0x5a);
  BuildOptions options = options_for(10, 6);
  options.weighting = Weighting::kTf;  // one image: IDF would weigh the word 0
  const Vocabulary vocabulary = Vocabulary::build({DescriptorView{same.data(), 50, 32}}, options);
  EXPECT_EQ(vocabulary.word_count(), 1u);
  EXPECT_EQ(vocabulary.node_count(), 2u);
  EXPECT_EQ(vocabulary.node_descriptor(1)[0], 0x5a);
}

TEST(VocabularyBuild, ReportsProgressUpToEveryDescriptor) {
  std::mt19937_64 rng(5);
  const DescriptorMatrix rows = test::clustered_descriptors(2000, 32, 20, 0.1, rng);
  BuildOptions options = options_for(6, 3);
  BuildProgress last;
  int calls = 0;
  options.progress = [&](const BuildProgress& progress) {
    ++calls;
    EXPECT_LE(progress.clustered_descriptors, progress.total_descriptors);
    last = progress;
  };
  const Vocabulary vocabulary = Vocabulary::build(split(rows, 5), options);
  EXPECT_GE(calls, 1);
  EXPECT_EQ(last.total_descriptors, rows.rows());
  EXPECT_EQ(last.clustered_descriptors, rows.rows());
  EXPECT_EQ(last.nodes, vocabulary.node_count());
}

}  // namespace
}  // namespace binbow
