// The reference implementation lives in this *_test.cpp file so the test glob
// picks it up; its header is tests/core/reference_tree.h.
#include "core/reference_tree.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <functional>

namespace binbow::test {

VocabularyTree random_tree(std::mt19937_64& rng, std::size_t code_size, std::uint32_t k,
                           std::uint32_t levels, double leaf_probability) {
  VocabularyTree t;
  t.code_size = code_size;
  t.branching = k;
  t.levels = levels;
  t.parent.push_back(0);
  t.descriptors.resize(code_size, 0);
  t.weights.push_back(0);
  std::vector<std::uint32_t> frontier{0}, depth{0};
  std::uniform_real_distribution<double> u(0, 1);
  for (std::size_t f = 0; f < frontier.size(); ++f) {
    const std::uint32_t node = frontier[f];
    if (depth[node] == levels) continue;
    if (node != 0 && u(rng) < leaf_probability) continue;
    const std::uint32_t count = 1 + static_cast<std::uint32_t>(rng() % k);
    for (std::uint32_t c = 0; c < count; ++c) {
      const auto id = static_cast<std::uint32_t>(t.parent.size());
      t.parent.push_back(node);
      for (std::size_t b = 0; b < code_size; ++b)
        t.descriptors.push_back(static_cast<std::uint8_t>(rng()));
      t.weights.push_back(u(rng) < 0.05 ? 0.0f : static_cast<float>(u(rng) * 3));
      depth.push_back(depth[node] + 1);
      frontier.push_back(id);
    }
  }
  return t;
}

ReferenceVocabulary::ReferenceVocabulary(const VocabularyTree& tree) : tree_(tree) {
  std::vector<ReferenceNode*> by_id(tree.node_count());
  root_ = std::make_unique<ReferenceNode>();
  by_id[0] = root_.get();
  for (std::size_t i = 1; i < tree.node_count(); ++i) {
    auto node = std::make_unique<ReferenceNode>();
    node->original_id = i;
    node->descriptor.assign(tree.descriptors.begin() + i * tree.code_size,
                            tree.descriptors.begin() + (i + 1) * tree.code_size);
    node->weight = tree.weights[i];
    by_id[i] = node.get();
    by_id[tree.parent[i]]->children.push_back(std::move(node));
  }
  // DBoW2 numbering, recursively: children get consecutive ids, then recurse.
  std::uint32_t next = 1;
  std::function<void(ReferenceNode*)> number = [&](ReferenceNode* n) {
    for (auto& c : n->children) c->dbow2_id = next++;
    for (auto& c : n->children) number(c.get());
  };
  number(root_.get());
  // Words: leaves in DBoW2 node order.
  std::vector<ReferenceNode*> in_order(tree.node_count());
  std::function<void(ReferenceNode*)> collect = [&](ReferenceNode* n) {
    in_order[n->dbow2_id] = n;
    for (auto& c : n->children) collect(c.get());
  };
  collect(root_.get());
  for (ReferenceNode* n : in_order)
    if (n->children.empty()) {
      n->word = static_cast<int>(word_count_++);
      word_weight_.push_back(n->weight);
    }
}

std::pair<int, std::uint32_t> ReferenceVocabulary::descend(const std::uint8_t* d,
                                                           std::uint32_t level_depth) const {
  const ReferenceNode* n = root_.get();
  std::uint32_t depth = 0, level_node = 0;
  while (!n->children.empty()) {
    const ReferenceNode* best = nullptr;
    int best_distance = 1 << 30;
    for (const auto& c : n->children) {
      int dist = 0;
      for (std::size_t b = 0; b < tree_.code_size; ++b)
        dist += __builtin_popcount(static_cast<unsigned>(d[b] ^ c->descriptor[b]));
      if (dist < best_distance) best_distance = dist, best = c.get();
    }
    n = best;
    if (++depth == level_depth) level_node = n->dbow2_id;
  }
  if (depth < level_depth) level_node = n->dbow2_id;
  return {n->word, level_node};
}

std::vector<double> ReferenceVocabulary::transform(const DescriptorView& d, Scoring scoring) const {
  std::vector<double> v(word_count_, 0.0);
  const Weighting w = tree_.weighting;
  for (std::size_t i = 0; i < d.rows; ++i) {
    const int word = descend(d.row(i), 0).first;
    const double weight = word_weight_[word];
    if (weight <= 0) continue;
    if (w == Weighting::kTf || w == Weighting::kTfIdf)
      v[word] += weight;
    else
      v[word] = weight;
  }
  if (scoring == Scoring::kDotProduct) {
    if (w == Weighting::kTf || w == Weighting::kTfIdf) {
      double distinct = 0;
      for (double x : v) distinct += x != 0;
      if (distinct > 0)
        for (double& x : v) x /= distinct;
    }
    return v;
  }
  double norm = 0;
  for (double x : v) norm += scoring == Scoring::kL2 ? x * x : std::fabs(x);
  if (scoring == Scoring::kL2) norm = std::sqrt(norm);
  if (norm > 0)
    for (double& x : v) x /= norm;
  return v;
}

double reference_score(const std::vector<double>& a, const std::vector<double>& b,
                       Scoring scoring) {
  double s = 0;
  switch (scoring) {
    case Scoring::kL1:
      for (std::size_t i = 0; i < a.size(); ++i) s += std::fabs(a[i] - b[i]);
      return 1.0 - 0.5 * s;
    case Scoring::kL2:
      for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
      return s >= 1 ? 1.0 : 1.0 - std::sqrt(1.0 - s);
    case Scoring::kChiSquare:
      for (std::size_t i = 0; i < a.size(); ++i)
        if (a[i] > 0 && b[i] > 0) s += a[i] * b[i] / (a[i] + b[i]);
      return 2 * s;
    case Scoring::kKL:
      for (std::size_t i = 0; i < a.size(); ++i)
        if (a[i] > 0)
          s += b[i] > 0 ? a[i] * std::log(a[i] / b[i])
                        : a[i] * (std::log(a[i]) - std::log(DBL_EPSILON));
      return s;
    case Scoring::kBhattacharyya:
      for (std::size_t i = 0; i < a.size(); ++i) s += std::sqrt(a[i] * b[i]);
      return s;
    case Scoring::kDotProduct:
      for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
      return s;
  }
  return s;
}

TEST(ReferenceTree, NumbersLeavesInDbow2Order) {
  std::mt19937_64 rng(3);
  const VocabularyTree t = random_tree(rng, 32, 4, 3);
  ReferenceVocabulary ref(t);
  EXPECT_GT(ref.word_count(), 3u);
}

}  // namespace binbow::test
