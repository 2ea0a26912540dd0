#include "binbow/bow_vector.h"

#include <algorithm>
#include <string>

#include "binbow/error.h"

namespace binbow {

BowVector::BowVector(std::vector<BowEntry> entries) : entries_(std::move(entries)) {
  for (std::size_t i = 1; i < entries_.size(); ++i)
    if (entries_[i - 1].word >= entries_[i].word)
      throw InvalidArgument(
          "BowVector entries must be sorted by strictly increasing word id (entry " +
          std::to_string(i) + ")");
}

float BowVector::value(WordId word) const {
  const auto it = std::lower_bound(entries_.begin(), entries_.end(), word,
                                   [](const BowEntry& e, WordId w) { return e.word < w; });
  return it != entries_.end() && it->word == word ? it->value : 0.0f;
}

Span<std::uint32_t> FeatureVector::features_of(NodeId node) const {
  const auto it = std::lower_bound(nodes_.begin(), nodes_.end(), node);
  if (it == nodes_.end() || *it != node) return {};
  return features(static_cast<std::size_t>(it - nodes_.begin()));
}

FeatureVector FeatureVector::from_assignment(const NodeId* node_of_feature, std::size_t count) {
  std::vector<std::uint64_t> keys(count);
  for (std::size_t i = 0; i < count; ++i)
    keys[i] = (std::uint64_t{node_of_feature[i]} << 32) | static_cast<std::uint32_t>(i);
  std::sort(keys.begin(), keys.end());
  FeatureVector fv;
  fv.features_.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const auto node = static_cast<NodeId>(keys[i] >> 32);
    if (fv.nodes_.empty() || fv.nodes_.back() != node) {
      if (!fv.nodes_.empty()) fv.offsets_.push_back(static_cast<std::uint32_t>(i));
      fv.nodes_.push_back(node);
    }
    fv.features_.push_back(static_cast<std::uint32_t>(keys[i]));
  }
  if (!fv.nodes_.empty()) fv.offsets_.push_back(static_cast<std::uint32_t>(count));
  return fv;
}

FeatureVector FeatureVector::from_arrays(std::vector<NodeId> nodes,
                                         std::vector<std::uint32_t> offsets,
                                         std::vector<std::uint32_t> features) {
  if (offsets.size() != nodes.size() + 1 || offsets.front() != 0 ||
      offsets.back() != features.size())
    throw InvalidArgument("FeatureVector: offsets do not match nodes and features");
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (i > 0 && nodes[i - 1] >= nodes[i])
      throw InvalidArgument("FeatureVector: nodes are not strictly increasing");
    if (offsets[i] >= offsets[i + 1])
      throw InvalidArgument("FeatureVector: a node has no features");
  }
  FeatureVector fv;
  fv.nodes_ = std::move(nodes);
  fv.offsets_ = std::move(offsets);
  fv.features_ = std::move(features);
  return fv;
}

void FeatureVector::clear() noexcept {
  nodes_.clear();
  offsets_.assign(1, 0);
  features_.clear();
}

}  // namespace binbow
