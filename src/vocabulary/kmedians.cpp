#include "vocabulary/kmedians.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "core/kernels.h"
#include "core/parallel_for.h"

namespace binbow::detail {
namespace {

// Below this many rows per chunk, splitting a node costs more than it saves.
constexpr std::size_t kMinRowsPerChunk = 16384;
// Eight 8-bit counters per byte of a descriptor overflow after 255 additions.
constexpr std::size_t kPackedFlushInterval = 255;
// Recount every cluster's bits instead of moving rows one by one when more
// than 1/kRecountRatio of the rows moved.
constexpr std::size_t kRecountRatio = 4;

// kByteLanes[v] has byte b equal to bit b of v: adding it to a 64-bit word
// counts the eight bits of one descriptor byte at once.
constexpr std::array<std::uint64_t, 256> make_byte_lanes() {
  std::array<std::uint64_t, 256> lanes{};
  for (unsigned v = 0; v < 256; ++v) {
    std::uint64_t word = 0;
    for (unsigned b = 0; b < 8; ++b) word |= static_cast<std::uint64_t>((v >> b) & 1u) << (8 * b);
    lanes[v] = word;
  }
  return lanes;
}
constexpr std::array<std::uint64_t, 256> kByteLanes = make_byte_lanes();

// kBitValues[v][b] is bit b of v, as eight 32-bit lanes the compiler adds with
// two vector instructions.
struct BitValues {
  std::int32_t bits[256][8];
};
constexpr BitValues make_bit_values() {
  BitValues values{};
  for (unsigned v = 0; v < 256; ++v) {
    for (unsigned b = 0; b < 8; ++b) values.bits[v][b] = static_cast<std::int32_t>((v >> b) & 1u);
  }
  return values;
}
constexpr BitValues kBitValues = make_bit_values();

}  // namespace

std::uint64_t SplitMix64::below(std::uint64_t bound) {
  // Rejecting the lowest 2^64 mod bound values keeps the draw exactly uniform.
  const std::uint64_t threshold = (0 - bound) % bound;
  for (;;) {
    const std::uint64_t value = next();
    if (value >= threshold) return value % bound;
  }
}

std::uint64_t child_seed(std::uint64_t parent, std::uint64_t index) {
  SplitMix64 mixer(parent ^ (0xd1b54a32d192ed03ull * (index + 1)));
  return mixer.next();
}

KMedians::KMedians(std::size_t code_size, std::uint32_t k)
    : code_size_(code_size),
      bits_(code_size * 8),
      k_(k),
      centres_(k * code_size),
      counts_(k * code_size * 8),
      members_(k),
      dirty_(k) {}

template <class Body>
void KMedians::for_chunks(Body&& body) {
  parallel_for(threads_, chunks_.size(), [&](std::size_t c, unsigned) { body(chunks_[c]); });
}

void KMedians::cluster(const std::uint8_t* rows, std::size_t n, std::uint64_t seed,
                       unsigned max_iterations, unsigned threads, std::uint32_t* assignment,
                       std::uint32_t* distance) {
  rows_ = rows;
  n_ = n;
  converged_ = false;
  iterations_ = 0;
  reseeded_ = 0;
  count_ = 0;
  std::fill(members_.begin(), members_.end(), 0);
  if (n <= k_) {
    cluster_distinct(rows, n, assignment, distance);
    return;
  }

  const std::size_t chunk_count =
      std::max<std::size_t>(1, std::min<std::size_t>(threads, n / kMinRowsPerChunk));
  threads_ = static_cast<unsigned>(chunk_count);
  chunks_.resize(chunk_count);
  for (std::size_t c = 0; c < chunk_count; ++c) {
    Chunk& chunk = chunks_[c];
    chunk.begin = n * c / chunk_count;
    chunk.end = n * (c + 1) / chunk_count;
    chunk.packed.assign(k_ * code_size_, 0);
    if (chunk_count > 1) {
      chunk.counts.assign(k_ * bits_, 0);
      chunk.members.assign(k_, 0);
      chunk.dirty.assign(k_, 0);
    }
  }
  if (scratch_index_.size() < n) {
    scratch_index_.resize(n);
    scratch_distance_.resize(n);
  }

  seed_centres(seed, assignment, distance);
  count_bits(assignment);
  std::fill(dirty_.begin(), dirty_.begin() + count_, std::uint8_t{1});
  while (iterations_ < max_iterations) {
    if (!update_centres()) {
      converged_ = true;
      break;
    }
    ++iterations_;
    std::size_t moved = assign(assignment, distance);
    moved += repair_empty_clusters(assignment, distance);
    if (moved == 0) {
      converged_ = true;
      break;
    }
  }
}

void KMedians::cluster_distinct(const std::uint8_t* rows, std::size_t n, std::uint32_t* assignment,
                                std::uint32_t* distance) {
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* row = rows + i * code_size_;
    std::uint32_t c = 0;
    while (c < count_ && std::memcmp(centre(c), row, code_size_) != 0) ++c;
    if (c == count_) std::memcpy(centres_.data() + count_++ * code_size_, row, code_size_);
    assignment[i] = c;
    distance[i] = 0;
    ++members_[c];
  }
  converged_ = true;
}

void KMedians::seed_centres(std::uint64_t seed, std::uint32_t* assignment,
                            std::uint32_t* distance) {
  const Kernels& kernel = kernels();
  SplitMix64 rng(seed);
  const std::size_t first = rng.below(n_);
  std::memcpy(centres_.data(), rows_ + first * code_size_, code_size_);
  count_ = 1;
  for_chunks([&](Chunk& chunk) {
    const std::size_t length = chunk.end - chunk.begin;
    kernel.nearest(rows_ + chunk.begin * code_size_, length, centres_.data(), 1, code_size_,
                   scratch_index_.data() + chunk.begin, distance + chunk.begin);
    std::uint64_t sum = 0;
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      assignment[i] = 0;
      sum += static_cast<std::uint64_t>(distance[i]) * distance[i];
    }
    chunk.squared_sum = sum;
  });

  while (count_ < k_) {
    std::uint64_t total = 0;
    for (const Chunk& chunk : chunks_) total += chunk.squared_sum;
    if (total == 0) break;  // every row equals a centre: fewer distinct rows than k
    std::uint64_t target = rng.below(total);
    std::size_t pick = n_ - 1;
    for (const Chunk& chunk : chunks_) {
      if (target >= chunk.squared_sum) {
        target -= chunk.squared_sum;
        continue;
      }
      std::uint64_t cumulative = 0;
      for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
        cumulative += static_cast<std::uint64_t>(distance[i]) * distance[i];
        if (cumulative > target) {
          pick = i;
          break;
        }
      }
      break;
    }
    const std::uint32_t c = count_++;
    std::uint8_t* new_centre = centres_.data() + c * code_size_;
    std::memcpy(new_centre, rows_ + pick * code_size_, code_size_);
    for_chunks([&](Chunk& chunk) {
      const std::size_t length = chunk.end - chunk.begin;
      kernel.nearest(rows_ + chunk.begin * code_size_, length, new_centre, 1, code_size_,
                     scratch_index_.data() + chunk.begin, scratch_distance_.data() + chunk.begin);
      std::uint64_t sum = 0;
      for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
        if (scratch_distance_[i] < distance[i]) {
          distance[i] = scratch_distance_[i];
          assignment[i] = c;
        }
        sum += static_cast<std::uint64_t>(distance[i]) * distance[i];
      }
      chunk.squared_sum = sum;
    });
  }
}

void KMedians::count_bits(const std::uint32_t* assignment) {
  std::fill(counts_.begin(), counts_.end(), 0);
  std::fill(members_.begin(), members_.end(), 0);
  const bool merge = chunks_.size() > 1;
  for_chunks([&](Chunk& chunk) {
    std::int32_t* counts = merge ? chunk.counts.data() : counts_.data();
    std::uint64_t* packed = chunk.packed.data();
    auto flush = [&] {
      for (std::uint32_t c = 0; c < count_; ++c) {
        for (std::size_t j = 0; j < code_size_; ++j) {
          std::uint64_t& word = packed[c * code_size_ + j];
          if (word == 0) continue;
          std::int32_t* bit_counts = counts + c * bits_ + j * 8;
          for (unsigned b = 0; b < 8; ++b) {
            bit_counts[b] += static_cast<std::int32_t>((word >> (8 * b)) & 0xffu);
          }
          word = 0;
        }
      }
    };
    std::size_t since_flush = 0;
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      const std::uint8_t* row = rows_ + i * code_size_;
      std::uint64_t* target = packed + assignment[i] * code_size_;
      for (std::size_t j = 0; j < code_size_; ++j) target[j] += kByteLanes[row[j]];
      if (++since_flush == kPackedFlushInterval) {
        flush();
        since_flush = 0;
      }
    }
    flush();
  });
  for (std::size_t i = 0; i < n_; ++i) ++members_[assignment[i]];
  if (merge) {
    for (Chunk& chunk : chunks_) {
      for (std::size_t i = 0; i < counts_.size(); ++i) counts_[i] += chunk.counts[i];
      std::fill(chunk.counts.begin(), chunk.counts.end(), 0);
    }
  }
}

bool KMedians::update_centres() {
  bool changed = false;
  for (std::uint32_t c = 0; c < count_; ++c) {
    if (!dirty_[c]) continue;
    dirty_[c] = 0;
    const std::int64_t size = members_[c];
    const std::int32_t* bit_counts = counts_.data() + c * bits_;
    std::uint8_t* bytes = centres_.data() + c * code_size_;
    for (std::size_t j = 0; j < code_size_; ++j) {
      unsigned byte = 0;
      for (unsigned b = 0; b < 8; ++b) {
        if (2 * static_cast<std::int64_t>(bit_counts[j * 8 + b]) >= size) byte |= 1u << b;
      }
      if (bytes[j] != byte) {
        bytes[j] = static_cast<std::uint8_t>(byte);
        changed = true;
      }
    }
  }
  return changed;
}

void KMedians::move_row(std::size_t row, std::uint32_t from, std::uint32_t to, std::int32_t* counts,
                        std::int32_t* members, std::uint8_t* dirty) const {
  const std::uint8_t* bytes = rows_ + row * code_size_;
  std::int32_t* from_counts = counts + from * bits_;
  std::int32_t* to_counts = counts + to * bits_;
  for (std::size_t j = 0; j < code_size_; ++j) {
    const std::int32_t* bits = kBitValues.bits[bytes[j]];
    std::int32_t* from_byte = from_counts + j * 8;
    std::int32_t* to_byte = to_counts + j * 8;
    for (unsigned b = 0; b < 8; ++b) {
      from_byte[b] -= bits[b];
      to_byte[b] += bits[b];
    }
  }
  --members[from];
  ++members[to];
  dirty[from] = 1;
  dirty[to] = 1;
}

std::size_t KMedians::assign(std::uint32_t* assignment, std::uint32_t* distance) {
  const Kernels& kernel = kernels();
  for_chunks([&](Chunk& chunk) {
    kernel.nearest(rows_ + chunk.begin * code_size_, chunk.end - chunk.begin, centres_.data(),
                   count_, code_size_, scratch_index_.data() + chunk.begin, distance + chunk.begin);
    std::size_t moved = 0;
    for (std::size_t i = chunk.begin; i < chunk.end; ++i)
      moved += scratch_index_[i] != assignment[i];
    chunk.moved = moved;
  });
  std::size_t moved = 0;
  for (const Chunk& chunk : chunks_) moved += chunk.moved;
  if (moved == 0) return 0;
  // Moving one row updates 2 × bits counters; recounting costs about a
  // quarter of that per row, so recount when many rows moved.
  if (moved * kRecountRatio > n_) {
    std::copy_n(scratch_index_.data(), n_, assignment);
    count_bits(assignment);
    std::fill(dirty_.begin(), dirty_.begin() + count_, std::uint8_t{1});
    return moved;
  }
  const bool merge = chunks_.size() > 1;
  for_chunks([&](Chunk& chunk) {
    if (chunk.moved == 0) return;
    std::int32_t* counts = merge ? chunk.counts.data() : counts_.data();
    std::int32_t* members = merge ? chunk.members.data() : members_.data();
    std::uint8_t* dirty = merge ? chunk.dirty.data() : dirty_.data();
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      const std::uint32_t nearest = scratch_index_[i];
      if (nearest == assignment[i]) continue;
      move_row(i, assignment[i], nearest, counts, members, dirty);
      assignment[i] = nearest;
    }
  });
  if (!merge) return moved;
  for (Chunk& chunk : chunks_) {
    if (chunk.moved == 0) continue;
    for (std::uint32_t c = 0; c < count_; ++c) {
      members_[c] += chunk.members[c];
      chunk.members[c] = 0;
      dirty_[c] |= chunk.dirty[c];
      chunk.dirty[c] = 0;
    }
    for (std::size_t i = 0; i < count_ * bits_; ++i) {
      counts_[i] += chunk.counts[i];
      chunk.counts[i] = 0;
    }
  }
  return moved;
}

std::size_t KMedians::repair_empty_clusters(std::uint32_t* assignment, std::uint32_t* distance) {
  const Kernels& kernel = kernels();
  std::size_t moved = 0;
  // Each repair takes the farthest row to distance 0 and moves no row away
  // from a nearer centre, so the total distance falls and the loop ends. A
  // repair can empty the farthest row's old cluster, hence the rescan.
  for (;;) {
    const std::uint32_t c = static_cast<std::uint32_t>(
        std::find(members_.begin(), members_.begin() + count_, 0) - members_.begin());
    if (c == count_) return moved;
    const std::size_t farthest =
        static_cast<std::size_t>(std::max_element(distance, distance + n_) - distance);
    if (distance[farthest] == 0) return moved;  // impossible (see kmedians.h); never spin
    ++reseeded_;
    std::uint8_t* new_centre = centres_.data() + c * code_size_;
    std::memcpy(new_centre, rows_ + farthest * code_size_, code_size_);
    kernel.nearest(rows_, n_, new_centre, 1, code_size_, scratch_index_.data(),
                   scratch_distance_.data());
    for (std::size_t i = 0; i < n_; ++i) {
      const std::uint32_t d = scratch_distance_[i];
      if (d < distance[i] || (d == distance[i] && c < assignment[i])) {
        move_row(i, assignment[i], c, counts_.data(), members_.data(), dirty_.data());
        assignment[i] = c;
        distance[i] = d;
        ++moved;
      }
    }
  }
}

}  // namespace binbow::detail
