// A deliberately naive vocabulary for tests: a pointer tree, exhaustive
// greedy descent, DBoW2's transform written out with doubles.
#pragma once

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "binbow/vocabulary.h"

namespace binbow::test {

// A random tree in breadth-first (not DBoW2) order: random child counts in
// [1, k], leaves at varying depths, some zero weights (stop words).
VocabularyTree random_tree(std::mt19937_64& rng, std::size_t code_size, std::uint32_t k,
                           std::uint32_t levels, double leaf_probability = 0.15);

struct ReferenceNode {
  std::size_t original_id = 0;
  std::vector<std::uint8_t> descriptor;
  float weight = 0;
  std::vector<std::unique_ptr<ReferenceNode>> children;
  int word = -1;  // DBoW2 word id (leaves)
  std::uint32_t dbow2_id = 0;
};

class ReferenceVocabulary {
 public:
  explicit ReferenceVocabulary(const VocabularyTree& tree);
  // Word id and DBoW2 node id at depth `level_depth` (or the leaf).
  std::pair<int, std::uint32_t> descend(const std::uint8_t* d, std::uint32_t level_depth) const;
  // Dense BoW vector (index = word id), DBoW2's weighting and normalisation.
  std::vector<double> transform(const DescriptorView& d, Scoring scoring) const;
  std::size_t word_count() const { return word_count_; }

 private:
  VocabularyTree tree_;
  std::unique_ptr<ReferenceNode> root_;
  std::vector<float> word_weight_;
  std::size_t word_count_ = 0;
};

// DBoW2's score definitions computed on dense vectors.
double reference_score(const std::vector<double>& a, const std::vector<double>& b, Scoring scoring);

}  // namespace binbow::test
