// The direct index's codec: a FeatureVector packed into a few bytes per feature.
#include "binbow/database.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <utility>

#include "binbow/error.h"
#include "core/little_endian.h"
#include "database/database_impl.h"

namespace binbow {

namespace detail {

PackedFeatureVector::PackedFeatureVector(const FeatureVector& features)
    : node_count_(static_cast<std::uint32_t>(features.size())),
      feature_count_(static_cast<std::uint32_t>(features.feature_count())) {
  const auto& indices = features.feature_indices();
  bool partition = node_count_ <= 0x10000;
  if (partition) {
    // Every index below the count and none twice: a branch-free pass, a
    // byte per index so that no store waits for the one before (neighbours
    // would share a word of a bit set).
    std::vector<std::uint8_t> seen(std::size_t{feature_count_} + 1, 0);
    const std::size_t beyond = feature_count_;  // out-of-range indices land here
    std::uint8_t repeated = 0;
    for (std::uint32_t index : indices) {
      const std::size_t at = index < feature_count_ ? index : beyond;
      repeated |= seen[at];
      seen[at] = 1;
    }
    partition = repeated == 0 && seen[beyond] == 0;
  }
  if (partition) {
    layout_ = node_count_ <= 0x80    ? Layout::kPartition7
              : node_count_ <= 0x100 ? Layout::kPartition8
                                     : Layout::kPartition16;
  } else {
    const bool wide =
        feature_count_ > 0xFFFF ||
        std::any_of(indices.begin(), indices.end(), [](std::uint32_t i) { return i > 0xFFFF; });
    layout_ = wide ? Layout::kRows32 : Layout::kRows16;
  }
  // Node ids are increasing: each is stored as its step from the previous
  // one (the first from 0), 7 bits per byte (LEB128), or, when shorter, each
  // run of consecutive ids as the step to its first from the end of the
  // previous run (from 0) and its length - 1. Siblings are consecutive ids:
  // a direct index 4 levels up a k=10 L=6 tree takes ~1.2 bytes per node as
  // steps, ~0.4 as runs, against 4 for the ids.
  const auto leb128_bytes = [](std::uint32_t value) {
    std::uint32_t bytes = 1;
    for (; value >= 0x80; value >>= 7) ++bytes;
    return bytes;
  };
  const auto for_each_run = [&](const auto& visit) {
    NodeId end = 0;  // of the previous run
    for (std::size_t node = 0; node < node_count_;) {
      std::size_t last = node;
      while (last + 1 < node_count_ && features.node(last + 1) == features.node(last) + 1) ++last;
      visit(features.node(node) - end, static_cast<std::uint32_t>(last - node));
      end = features.node(last) + 1;
      node = last + 1;
    }
  };
  std::uint32_t step_bytes = 0, run_bytes = 0;
  for (std::size_t node = 0; node < node_count_; ++node)
    step_bytes += leb128_bytes(features.node(node) - (node > 0 ? features.node(node - 1) : 0));
  for_each_run([&](std::uint32_t step, std::uint32_t more) {
    run_bytes += leb128_bytes(step) + leb128_bytes(more);
  });
  node_runs_ = run_bytes < step_bytes;
  node_bytes_ = node_runs_ ? run_bytes : step_bytes;
  bytes_.reset(new std::uint8_t[packed_size()]);
  std::uint8_t* out = bytes_.get();
  const auto put_leb128 = [&](std::uint32_t value) {
    for (; value >= 0x80; value >>= 7) *out++ = static_cast<std::uint8_t>((value & 0x7F) | 0x80);
    *out++ = static_cast<std::uint8_t>(value);
  };
  if (node_runs_) {
    for_each_run([&](std::uint32_t step, std::uint32_t more) {
      put_leb128(step);
      put_leb128(more);
    });
  } else {
    for (std::size_t node = 0; node < node_count_; ++node)
      put_leb128(features.node(node) - (node > 0 ? features.node(node - 1) : 0));
  }
  if (layout_ == Layout::kPartition7) {
    // Feature f's 7 bits start at bit 7 f, from the low bit of each byte:
    // each feature's node position, then eight features per 7 bytes.
    std::vector<std::uint8_t> slots((std::size_t{feature_count_} + 7) / 8 * 8, 0);
    for (std::size_t node = 0; node < node_count_; ++node)
      for (std::uint32_t index : features.features(node))
        slots[index] = static_cast<std::uint8_t>(node);
    std::uint8_t* const end = bytes_.get() + packed_size();
    for (std::size_t f = 0; f < slots.size(); f += 8, out += 7) {
      std::uint64_t eight = 0;
      for (std::size_t k = 0; k < 8; ++k) eight |= std::uint64_t{slots[f + k]} << (7 * k);
      std::memcpy(out, &eight, std::min<std::size_t>(7, static_cast<std::size_t>(end - out)));
    }
    return;
  }
  if (partition) {
    const std::size_t width = layout_ == Layout::kPartition8 ? 1 : 2;
    for (std::size_t node = 0; node < node_count_; ++node) {
      const auto slot = static_cast<std::uint16_t>(node);
      if (width == 1) {
        for (std::uint32_t index : features.features(node))
          out[index] = static_cast<std::uint8_t>(slot);
      } else {
        for (std::uint32_t index : features.features(node))
          std::memcpy(out + std::size_t{index} * 2, &slot, 2);  // little-endian
      }
    }
    return;
  }
  const std::size_t width = layout_ == Layout::kRows32 ? 4 : 2;
  const auto put = [&](std::uint32_t v) {
    std::memcpy(out, &v, width);  // little-endian: the low bytes
    out += width;
  };
  for (std::size_t i = 1; i <= node_count_; ++i) put(features.offsets()[i]);
  for (std::uint32_t index : indices) put(index);
}

std::size_t PackedFeatureVector::packed_size() const noexcept {
  const std::size_t nodes = node_bytes_;
  switch (layout_) {
    case Layout::kPartition7:
      return nodes + (std::size_t{feature_count_} * 7 + 7) / 8;
    case Layout::kPartition8:
      return nodes + feature_count_;
    case Layout::kPartition16:
      return nodes + std::size_t{feature_count_} * 2;
    case Layout::kRows16:
      return nodes + (std::size_t{node_count_} + feature_count_) * 2;
    case Layout::kRows32:
      return nodes + (std::size_t{node_count_} + feature_count_) * 4;
  }
  return 0;
}

void PackedFeatureVector::encode(std::uint8_t* out) const noexcept {
  out[0] = static_cast<std::uint8_t>(static_cast<unsigned>(layout_) | (node_runs_ ? kNodeRuns : 0));
  store_le<std::uint32_t>(out + 1, node_bytes_);
  if (packed_size() > 0) std::memcpy(out + 5, bytes_.get(), packed_size());
}

bool PackedFeatureVector::read_leb128(const std::uint8_t*& at, const std::uint8_t* end,
                                      std::uint64_t& value) noexcept {
  value = 0;
  for (unsigned shift = 0; shift < 35; shift += 7) {
    if (at == end) return false;
    const std::uint8_t byte = *at++;
    value |= std::uint64_t{byte & 0x7Fu} << shift;
    if ((byte & 0x80) == 0) return true;
  }
  return false;
}

template <class Visit>
bool PackedFeatureVector::for_each_node(const Visit& visit) const {
  const std::uint8_t* at = bytes_.get();
  const std::uint8_t* const end = at + node_bytes_;
  std::uint64_t id = 0;
  for (std::uint32_t node = 0; node < node_count_;) {
    std::uint64_t step, more = 0;
    if (!read_leb128(at, end, step) || (node_runs_ && !read_leb128(at, end, more))) return false;
    // Steps after the first are at least 1 (runs: from the previous run's end).
    if (node > 0 && step == 0 && !node_runs_) return false;
    id += step;
    if (more >= node_count_ - node || id + more > 0xFFFFFFFFu) return false;
    for (std::uint64_t i = 0; i <= more; ++i, ++node) visit(static_cast<NodeId>(id + i));
    if (node_runs_) id += more + 1;
  }
  return at == end;
}

PackedFeatureVector PackedFeatureVector::decode(const std::uint8_t* data, std::size_t size,
                                                std::uint32_t node_count,
                                                std::uint32_t feature_count,
                                                std::uint64_t node_limit) {
  if (size < 5) throw InvalidArgument("shorter than its layout");
  PackedFeatureVector packed;
  packed.node_count_ = node_count;
  packed.feature_count_ = feature_count;
  const unsigned layout = data[0] & ~kNodeRuns;
  if (layout > static_cast<unsigned>(Layout::kPartition7))
    throw InvalidArgument("unknown layout " + std::to_string(data[0]));
  packed.layout_ = static_cast<Layout>(layout);
  packed.node_runs_ = (data[0] & kNodeRuns) != 0;
  packed.node_bytes_ = load_le<std::uint32_t>(data + 1);
  const bool partition = packed.partition();
  const std::uint32_t most_nodes = packed.layout_ == Layout::kPartition7   ? 0x80u
                                   : packed.layout_ == Layout::kPartition8 ? 0x100u
                                                                           : 0x10000u;
  if (partition && node_count > most_nodes) throw InvalidArgument("too many nodes for its layout");
  if (packed.node_bytes_ > size - 5 || size - 5 != packed.packed_size())
    throw InvalidArgument(std::to_string(size - 5) + " bytes, not what its " +
                          std::to_string(node_count) + " nodes and " +
                          std::to_string(feature_count) + " features take");
  packed.bytes_.reset(new std::uint8_t[size - 5]);
  if (size > 5) std::memcpy(packed.bytes_.get(), data + 5, size - 5);
  NodeId largest = 0;
  if (!packed.for_each_node([&](NodeId id) { largest = id; }))
    throw InvalidArgument(
        "node ids are cut short, too large, not strictly increasing or followed by stray bytes");
  if (node_count > 0 && largest >= node_limit)
    throw InvalidArgument("node " + std::to_string(largest) + " is out of range");
  if (partition) {
    // Every feature names a node, and every node has a feature.
    std::vector<std::uint8_t> used(node_count, 0);
    for (std::size_t f = 0; f < feature_count; ++f) {
      const std::uint32_t slot = packed.slot(f);
      if (slot >= node_count) throw InvalidArgument("a feature names no node");
      used[slot] = 1;
    }
    if (std::find(used.begin(), used.end(), 0) != used.end())
      throw InvalidArgument("a node has no features");
    // The bits after the last feature's are zero: one encoding per vector.
    const std::size_t used_bits = std::size_t{7} * feature_count;
    if (packed.layout_ == Layout::kPartition7 && used_bits % 8 != 0 &&
        (packed.bytes_[size - 6] >> (used_bits % 8)) != 0)
      throw InvalidArgument("stray bits after the last feature");
  } else {
    const std::size_t width = packed.layout_ == Layout::kRows32 ? 4 : 2;
    std::uint32_t previous = 0;
    for (std::size_t node = 0; node < node_count; ++node) {
      const std::uint32_t end = packed.value(packed.node_bytes_ + node * width, width);
      if (end <= previous) throw InvalidArgument("a node has no features");
      previous = end;
    }
    if (previous != feature_count) throw InvalidArgument("node offsets do not end at its features");
  }
  return packed;
}

FeatureVector PackedFeatureVector::unpack() const {
  std::vector<NodeId> nodes;
  nodes.reserve(node_count_);
  for_each_node([&](NodeId id) { nodes.push_back(id); });
  const std::size_t nodes_bytes = node_bytes_;
  std::vector<std::uint32_t> offsets(std::size_t{node_count_} + 1, 0);
  std::vector<std::uint32_t> indices(feature_count_);
  if (partition()) {
    // Counting sort of the features by node; increasing index within a node.
    for (std::size_t f = 0; f < feature_count_; ++f) ++offsets[slot(f) + 1];
    for (std::size_t i = 0; i < node_count_; ++i) offsets[i + 1] += offsets[i];
    std::vector<std::uint32_t> next(offsets.begin(), offsets.end() - 1);
    for (std::uint32_t f = 0; f < feature_count_; ++f) indices[next[slot(f)]++] = f;
  } else {
    const std::size_t width = layout_ == Layout::kRows32 ? 4 : 2;
    std::size_t at = nodes_bytes;
    for (std::size_t i = 1; i <= node_count_; ++i, at += width) offsets[i] = value(at, width);
    for (auto& index : indices) {
      index = value(at, width);
      at += width;
    }
  }
  return FeatureVector::from_arrays(std::move(nodes), std::move(offsets), std::move(indices));
}

}  // namespace detail

}  // namespace binbow
