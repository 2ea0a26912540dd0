#include "binbow/vocabulary.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "binbow/error.h"
#include "core/kernels.h"
#include "core/scoring.h"
#include "vocabulary/radix_sort.h"
#include "vocabulary/vocabulary_block.h"

namespace binbow {

namespace {

const detail::VocabularyBlock& require(
    const std::shared_ptr<const detail::VocabularyBlock>& block) {
  if (!block) throw InvalidArgument("the vocabulary is empty (build or load one first)");
  return *block;
}

void check_tree(const VocabularyTree& tree) {
  auto fail = [](const std::string& problem) {
    throw InvalidArgument("invalid vocabulary tree: " + problem);
  };
  const std::size_t n = tree.node_count();
  if (tree.code_size == 0 || tree.code_size > detail::bbw::kMaxCodeSize)
    fail("descriptor size " + std::to_string(tree.code_size) + " is out of range 1..1024 bytes");
  if (tree.branching == 0 || tree.branching > detail::bbw::kMaxBranching)
    fail("branching factor " + std::to_string(tree.branching) + " is out of range 1..255");
  if (tree.levels == 0 || tree.levels > detail::bbw::kMaxLevels)
    fail("depth " + std::to_string(tree.levels) + " is out of range 1..32");
  if (n < 2 || n >= detail::kLeafBit) fail("node count " + std::to_string(n) + " is out of range");
  if (tree.descriptors.size() != n * tree.code_size)
    fail("descriptors hold " + std::to_string(tree.descriptors.size()) + " bytes, expected " +
         std::to_string(n * tree.code_size));
  if (tree.weights.size() != n)
    fail(std::to_string(tree.weights.size()) + " weights for " + std::to_string(n) + " nodes");
  if (!detail::valid_descriptor_name(tree.descriptor))
    fail("descriptor name \"" + tree.descriptor + "\" is not " + detail::kDescriptorNameRule);
  if (static_cast<unsigned>(tree.weighting) > 3 || static_cast<unsigned>(tree.scoring) > 5)
    fail("unknown weighting or scoring type");
}

// Thread-local buffers so that transform allocates nothing once warm.
struct Scratch {
  std::vector<WordId> words;
  std::vector<NodeId> nodes;
  std::vector<WordId> sorted;
  std::vector<NodeId> node_keys;
  std::vector<std::uint32_t> feature_ids;
  std::vector<std::uint32_t> buffer, buffer2;
  std::vector<double> values;
};

Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

bool must_normalise(Scoring scoring) {
  return scoring != Scoring::kDotProduct;
}

}  // namespace

Vocabulary::Vocabulary() = default;

Vocabulary::Vocabulary(std::shared_ptr<const detail::VocabularyBlock> block)
    : block_(std::move(block)), scoring_(block_->scoring) {}

Vocabulary Vocabulary::from_tree(const VocabularyTree& tree) {
  check_tree(tree);
  const std::size_t n = tree.node_count();

  // Children of every node, by increasing original id (compressed rows).
  std::vector<std::uint32_t> child_begin(n + 1, 0);
  for (std::size_t i = 1; i < n; ++i) {
    if (tree.parent[i] >= n || tree.parent[i] == i)
      throw InvalidArgument("invalid vocabulary tree: node " + std::to_string(i) +
                            " has parent id " + std::to_string(tree.parent[i]) +
                            " outside the tree");
    ++child_begin[tree.parent[i] + 1];
  }
  for (std::size_t i = 0; i < n; ++i) child_begin[i + 1] += child_begin[i];
  std::vector<std::uint32_t> children(n > 0 ? n - 1 : 0);
  {
    std::vector<std::uint32_t> fill(child_begin.begin(), child_begin.end() - 1);
    for (std::size_t i = 1; i < n; ++i)
      children[fill[tree.parent[i]]++] = static_cast<std::uint32_t>(i);
  }
  auto child_count = [&](std::size_t node) { return child_begin[node + 1] - child_begin[node]; };
  if (child_count(0) == 0)
    throw InvalidArgument("invalid vocabulary tree: the root has no children");

  // DBoW2's order: a node's children get consecutive ids, then each child's
  // subtree follows in turn (depth first).
  std::vector<std::uint32_t> old_of(1, 0);
  old_of.reserve(n);
  std::vector<std::uint32_t> new_first(n, 0);
  std::vector<std::uint8_t> depth(n, 0);
  std::vector<std::uint32_t> stack{0};
  while (!stack.empty()) {
    const std::uint32_t node = stack.back();
    stack.pop_back();
    const std::uint32_t count = child_count(node);
    if (count == 0) continue;
    if (count > tree.branching)
      throw InvalidArgument("invalid vocabulary tree: node " + std::to_string(node) + " has " +
                            std::to_string(count) + " children, more than the branching factor " +
                            std::to_string(tree.branching));
    if (depth[node] + 1u > tree.levels)
      throw InvalidArgument("invalid vocabulary tree: node " + std::to_string(node) +
                            " has children deeper than the declared " +
                            std::to_string(tree.levels) + " levels");
    new_first[node] = static_cast<std::uint32_t>(old_of.size());
    for (std::uint32_t c = 0; c < count; ++c) {
      const std::uint32_t child = children[child_begin[node] + c];
      depth[child] = static_cast<std::uint8_t>(depth[node] + 1);
      old_of.push_back(child);
    }
    for (std::uint32_t c = count; c-- > 0;) stack.push_back(children[child_begin[node] + c]);
  }
  if (old_of.size() != n)
    throw InvalidArgument("invalid vocabulary tree: " + std::to_string(n - old_of.size()) +
                          " nodes are not reachable from the root (a parent cycle?)");

  std::vector<std::uint8_t> descriptors(n * tree.code_size);
  std::vector<std::uint32_t> links(n);
  std::vector<std::uint8_t> counts(n);
  std::vector<float> word_weights;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t old = old_of[i];
    std::copy_n(tree.descriptors.data() + std::size_t{old} * tree.code_size, tree.code_size,
                descriptors.data() + i * tree.code_size);
    counts[i] = static_cast<std::uint8_t>(child_count(old));
    if (counts[i] == 0) {
      if (!std::isfinite(tree.weights[old]))
        throw InvalidArgument("invalid vocabulary tree: the weight of leaf node " +
                              std::to_string(old) + " is not a finite number");
      links[i] = static_cast<std::uint32_t>(word_weights.size()) | detail::kLeafBit;
      word_weights.push_back(tree.weights[old]);
    } else {
      links[i] = new_first[old];
    }
  }
  // The root's descriptor is never compared; store zeros so files do not
  // depend on what a source format kept there.
  std::fill_n(descriptors.data(), tree.code_size, std::uint8_t{0});

  auto block = std::make_shared<detail::VocabularyBlock>();
  block->owned = detail::encode_block(
      tree.code_size, tree.branching, tree.levels, tree.weighting, tree.scoring, tree.descriptor, n,
      word_weights.size(), descriptors.data(), links.data(), counts.data(), word_weights.data());
  detail::parse_block(*block, "vocabulary tree", LoadOptions{false});
  return Vocabulary(std::move(block));
}

VocabularyTree Vocabulary::to_tree() const {
  const auto& b = require(block_);
  VocabularyTree tree;
  tree.code_size = b.code_size;
  tree.branching = b.branching;
  tree.levels = b.levels;
  tree.weighting = b.weighting;
  tree.scoring = scoring_;
  tree.descriptor = b.descriptor;
  tree.parent.assign(b.node_count, 0);
  tree.descriptors.assign(b.tree.descriptors, b.tree.descriptors + b.node_count * b.code_size);
  tree.weights.assign(b.node_count, 0.0f);
  for (std::size_t n = 0; n < b.node_count; ++n) {
    const std::uint32_t count = b.tree.child_counts[n];
    if (count == 0) {
      tree.weights[n] = b.word_weights[b.tree.links[n] & ~detail::kLeafBit];
      continue;
    }
    for (std::uint32_t c = 0; c < count; ++c)
      tree.parent[b.tree.links[n] + c] = static_cast<NodeId>(n);
  }
  return tree;
}

bool Vocabulary::empty() const noexcept {
  return !block_;
}
std::size_t Vocabulary::code_size() const noexcept {
  return block_ ? block_->code_size : 0;
}
std::uint32_t Vocabulary::branching() const noexcept {
  return block_ ? block_->branching : 0;
}
std::uint32_t Vocabulary::levels() const noexcept {
  return block_ ? block_->levels : 0;
}
Weighting Vocabulary::weighting() const noexcept {
  return block_ ? block_->weighting : Weighting::kTfIdf;
}
Scoring Vocabulary::scoring() const noexcept {
  return scoring_;
}
std::size_t Vocabulary::node_count() const noexcept {
  return block_ ? block_->node_count : 0;
}
std::size_t Vocabulary::word_count() const noexcept {
  return block_ ? block_->word_count : 0;
}

std::uint32_t Vocabulary::checksum() const noexcept {
  return block_ ? detail::content_checksum(*block_, scoring_) : 0;
}

const std::string& Vocabulary::descriptor() const noexcept {
  static const std::string unknown;
  return block_ ? block_->descriptor : unknown;
}

std::string Vocabulary::description() const {
  if (!block_) return "empty vocabulary";
  return "k=" + std::to_string(branching()) + " L=" + std::to_string(levels()) + " " +
         to_string(weighting()) + " " + to_string(scoring()) + ", " + std::to_string(word_count()) +
         " words, " + std::to_string(node_count()) + " nodes, " + std::to_string(code_size() * 8) +
         "-bit descriptors";
}

namespace {
void check_node(const detail::VocabularyBlock& b, NodeId node) {
  if (node >= b.node_count)
    throw InvalidArgument("node id " + std::to_string(node) + " is out of range (" +
                          std::to_string(b.node_count) + " nodes)");
}
}  // namespace

const std::uint8_t* Vocabulary::node_descriptor(NodeId node) const {
  const auto& b = require(block_);
  check_node(b, node);
  return b.tree.descriptors + std::size_t{node} * b.code_size;
}

bool Vocabulary::is_leaf(NodeId node) const {
  const auto& b = require(block_);
  check_node(b, node);
  return b.tree.child_counts[node] == 0;
}

NodeId Vocabulary::first_child(NodeId node) const {
  const auto& b = require(block_);
  check_node(b, node);
  return b.tree.child_counts[node] == 0 ? 0 : b.tree.links[node];
}

std::uint32_t Vocabulary::child_count(NodeId node) const {
  const auto& b = require(block_);
  check_node(b, node);
  return b.tree.child_counts[node];
}

WordId Vocabulary::node_word(NodeId node) const {
  const auto& b = require(block_);
  check_node(b, node);
  if (b.tree.child_counts[node] != 0)
    throw InvalidArgument("node " + std::to_string(node) + " is not a leaf");
  return b.tree.links[node] & ~detail::kLeafBit;
}

const float* detail::word_weights(const Vocabulary& vocabulary) noexcept {
  return vocabulary.block_ ? vocabulary.block_->word_weights : nullptr;
}

float Vocabulary::word_weight(WordId word) const {
  const auto& b = require(block_);
  if (word >= b.word_count)
    throw InvalidArgument("word id " + std::to_string(word) + " is out of range (" +
                          std::to_string(b.word_count) + " words)");
  return b.word_weights[word];
}

std::vector<NodeId> Vocabulary::word_nodes() const {
  const auto& b = require(block_);
  std::vector<NodeId> nodes(b.word_count);
  for (std::size_t n = 0; n < b.node_count; ++n)
    if (b.tree.child_counts[n] == 0)
      nodes[b.tree.links[n] & ~detail::kLeafBit] = static_cast<NodeId>(n);
  return nodes;
}

namespace {
void check_descriptors(const detail::VocabularyBlock& b, const DescriptorView& d) {
  if (d.rows > 0 && d.code_size != b.code_size)
    throw InvalidArgument("descriptors have " + std::to_string(d.code_size) +
                          " bytes but the vocabulary's words have " + std::to_string(b.code_size) +
                          " (wrong descriptor type for this vocabulary?)");
}

std::uint32_t level_depth(const detail::VocabularyBlock& b, unsigned levels_up) {
  return levels_up >= b.levels ? 0 : b.levels - levels_up;
}
}  // namespace

WordId Vocabulary::quantize(const std::uint8_t* descriptor) const {
  const auto& b = require(block_);
  WordId word = 0;
  detail::kernels().descend(b.tree, descriptor, 1, &word, nullptr, 0);
  return word;
}

void Vocabulary::quantize(const DescriptorView& descriptors, WordId* words, NodeId* nodes,
                          unsigned levels_up) const {
  const auto& b = require(block_);
  check_descriptors(b, descriptors);
  detail::kernels().descend(b.tree, descriptors.data, descriptors.rows, words, nodes,
                            level_depth(b, levels_up));
}

double Vocabulary::mean_quantisation_error(const DescriptorView& descriptors) const {
  std::vector<WordId> words(descriptors.rows);
  quantize(descriptors, words.data());
  if (descriptors.rows == 0) return 0.0;
  const std::vector<NodeId> leaves = word_nodes();
  double total = 0;
  for (std::size_t i = 0; i < descriptors.rows; ++i)
    total += hamming_distance(descriptors.row(i), node_descriptor(leaves[words[i]]),
                              descriptors.code_size);
  return total / static_cast<double>(descriptors.rows);
}

void Vocabulary::words_to_bow(const WordId* words, std::size_t count, BowVector& bow) const {
  const auto& b = *block_;
  Scratch& s = scratch();
  // The weights of a big vocabulary are far apart in memory: fetch them all
  // now, so the misses overlap with one another and with the sort.
  for (std::size_t i = 0; i < count; ++i) __builtin_prefetch(b.word_weights + words[i]);
  s.sorted.assign(words, words + count);
  detail::radix_sort(s.sorted, nullptr, s.buffer, s.buffer2);
  bow.entries_.clear();
  s.values.clear();
  const bool accumulate = b.weighting == Weighting::kTf || b.weighting == Weighting::kTfIdf;
  for (std::size_t i = 0; i < s.sorted.size();) {
    const WordId word = s.sorted[i];
    std::size_t j = i + 1;
    while (j < s.sorted.size() && s.sorted[j] == word) ++j;
    const double weight = b.word_weights[word];
    if (weight > 0) {  // weight 0: a stop word (DBoW2 skips them too)
      bow.entries_.push_back({word, 0.0f});
      s.values.push_back(accumulate ? weight * static_cast<double>(j - i) : weight);
    }
    i = j;
  }
  if (must_normalise(scoring_)) {
    double norm = 0;
    if (scoring_ == Scoring::kL2) {
      for (double v : s.values) norm += v * v;
      norm = std::sqrt(norm);
    } else {
      for (double v : s.values) norm += std::fabs(v);
    }
    if (norm > 0)
      for (double& v : s.values) v /= norm;
  } else if (accumulate && !s.values.empty()) {
    // DBoW2 divides by the number of distinct words here, not of features.
    const double distinct = static_cast<double>(s.values.size());
    for (double& v : s.values) v /= distinct;
  }
  for (std::size_t i = 0; i < s.values.size(); ++i)
    bow.entries_[i].value = static_cast<float>(s.values[i]);
}

void Vocabulary::transform(const DescriptorView& descriptors, BowVector& bow) const {
  const auto& b = require(block_);
  check_descriptors(b, descriptors);
  Scratch& s = scratch();
  s.words.resize(descriptors.rows);
  detail::kernels().descend(b.tree, descriptors.data, descriptors.rows, s.words.data(), nullptr, 0);
  words_to_bow(s.words.data(), descriptors.rows, bow);
}

void Vocabulary::transform(const DescriptorView& descriptors, BowVector& bow,
                           FeatureVector& features, unsigned levels_up) const {
  const auto& b = require(block_);
  check_descriptors(b, descriptors);
  Scratch& s = scratch();
  s.words.resize(descriptors.rows);
  s.nodes.resize(descriptors.rows);
  detail::kernels().descend(b.tree, descriptors.data, descriptors.rows, s.words.data(),
                            s.nodes.data(), level_depth(b, levels_up));
  words_to_bow(s.words.data(), descriptors.rows, bow);

  // Group features by node with a stable sort, so indices stay increasing.
  s.node_keys.clear();
  s.feature_ids.clear();
  for (std::size_t i = 0; i < descriptors.rows; ++i) {
    if (b.word_weights[s.words[i]] <= 0) continue;
    s.node_keys.push_back(s.nodes[i]);
    s.feature_ids.push_back(static_cast<std::uint32_t>(i));
  }
  detail::radix_sort(s.node_keys, &s.feature_ids, s.buffer, s.buffer2);
  features.nodes_.clear();
  features.offsets_.assign(1, 0);
  for (std::size_t i = 0; i < s.node_keys.size(); ++i) {
    if (i > 0 && s.node_keys[i] == s.node_keys[i - 1]) continue;
    if (i > 0) features.offsets_.push_back(static_cast<std::uint32_t>(i));
    features.nodes_.push_back(s.node_keys[i]);
  }
  if (!features.nodes_.empty())
    features.offsets_.push_back(static_cast<std::uint32_t>(s.node_keys.size()));
  features.features_.assign(s.feature_ids.begin(), s.feature_ids.end());
}

double score_bow(const BowVector& a, const BowVector& b, Scoring scoring) {
  double sum = 0;
  const BowEntry* i = a.begin();
  const BowEntry* j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (i->word == j->word) {
      sum += detail::score_term(scoring, i->value, j->value);
      ++i;
      ++j;
    } else if (i->word < j->word) {
      ++i;
    } else {
      ++j;
    }
  }
  return detail::finish_score(scoring, sum, detail::score_base(scoring, a));
}

double Vocabulary::score(const BowVector& a, const BowVector& b) const {
  return score_bow(a, b, scoring_);
}

Vocabulary Vocabulary::with_scoring(Scoring scoring) const {
  Vocabulary copy = *this;
  copy.scoring_ = scoring;
  return copy;
}

}  // namespace binbow
