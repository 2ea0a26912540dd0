// Sparse bag-of-words vectors and the "feature vector" used as direct index.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "binbow/span.h"
#include "binbow/types.h"

namespace binbow {

// One non-zero component of a BoW vector.
struct BowEntry {
  WordId word;
  float value;

  friend bool operator==(const BowEntry& a, const BowEntry& b) {
    return a.word == b.word && a.value == b.value;
  }
};

// A sparse BoW vector: entries sorted by strictly increasing word id, values
// normalised as the vocabulary's scoring type requires. Contiguous storage.
class BowVector {
 public:
  BowVector() = default;
  // Takes entries that must already be sorted by strictly increasing word id;
  // throws InvalidArgument otherwise.
  explicit BowVector(std::vector<BowEntry> entries);

  std::size_t size() const noexcept { return entries_.size(); }
  bool empty() const noexcept { return entries_.empty(); }
  const BowEntry& operator[](std::size_t i) const { return entries_[i]; }
  const BowEntry* begin() const noexcept { return entries_.data(); }
  const BowEntry* end() const noexcept { return entries_.data() + entries_.size(); }
  const std::vector<BowEntry>& entries() const noexcept { return entries_; }

  // Value of `word`, 0 if absent (binary search).
  float value(WordId word) const;
  void clear() noexcept { entries_.clear(); }

  friend bool operator==(const BowVector& a, const BowVector& b) {
    return a.entries_ == b.entries_;
  }
  friend bool operator!=(const BowVector& a, const BowVector& b) { return !(a == b); }

 private:
  friend class Vocabulary;
  std::vector<BowEntry> entries_;
};

// Groups the features of one image by the vocabulary node they pass through at
// a chosen level (DBoW2's FeatureVector): node id → indices of the features
// (rows of the descriptor matrix) under that node. Nodes are sorted by id,
// feature indices increasing within a node. Stored as compressed rows: one
// allocation for all nodes, whatever their number.
class FeatureVector {
 public:
  FeatureVector() = default;

  // Number of distinct nodes.
  std::size_t size() const noexcept { return nodes_.size(); }
  bool empty() const noexcept { return nodes_.empty(); }
  NodeId node(std::size_t i) const { return nodes_[i]; }
  // Feature indices under the i-th node.
  Span<std::uint32_t> features(std::size_t i) const {
    return {features_.data() + offsets_[i], offsets_[i + 1] - offsets_[i]};
  }
  // Feature indices under `node`, empty if the node is absent (binary search).
  Span<std::uint32_t> features_of(NodeId node) const;
  // Total number of features.
  std::size_t feature_count() const noexcept { return features_.size(); }

  // Raw arrays: nodes (size()), offsets (size() + 1), features (feature_count()).
  const std::vector<NodeId>& nodes() const noexcept { return nodes_; }
  const std::vector<std::uint32_t>& offsets() const noexcept { return offsets_; }
  const std::vector<std::uint32_t>& feature_indices() const noexcept { return features_; }

  // Builds from `node_of_feature[i]` = node of feature i.
  static FeatureVector from_assignment(const NodeId* node_of_feature, std::size_t count);
  // Builds from raw arrays; throws InvalidArgument if they are inconsistent
  // (unsorted nodes, offsets not increasing, sizes that do not match).
  static FeatureVector from_arrays(std::vector<NodeId> nodes, std::vector<std::uint32_t> offsets,
                                   std::vector<std::uint32_t> features);

  void clear() noexcept;

  friend bool operator==(const FeatureVector& a, const FeatureVector& b) {
    return a.nodes_ == b.nodes_ && a.offsets_ == b.offsets_ && a.features_ == b.features_;
  }

 private:
  friend class Vocabulary;  // transform fills the arrays in place, reusing their capacity
  std::vector<NodeId> nodes_;
  std::vector<std::uint32_t> offsets_{0};
  std::vector<std::uint32_t> features_;
};

}  // namespace binbow
