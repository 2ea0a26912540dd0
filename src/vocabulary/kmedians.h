// k-medians clustering of binary descriptors under the Hamming distance: the
// step the vocabulary builder runs at every node of the tree.
//
// Semantics (DBoW2's TemplatedVocabulary::HKmeansStep, with its gaps closed):
// - n ≤ k rows: every distinct row becomes its own cluster, in row order.
// - otherwise k-means++ seeding: the first centre is a uniformly random row,
//   each next one a row drawn with probability ∝ its squared distance to the
//   nearest centre so far; seeding stops early when every row equals a centre
//   (so there are never two equal centres).
// - then, up to max_iterations times: every centre becomes the bitwise
//   majority of its members (bit set when at least half of the members have
//   it: DBoW2's FORB::meanValue rule, ties set the bit), and every row moves
//   to its nearest centre (lowest index on ties). Stops when no row moves.
// - a cluster left empty is re-seeded with the row farthest from its centre
//   (lowest index on ties). Such a row always exists: with more than k
//   distinct rows some row differs from every centre, and with at most k the
//   seeding already made every distinct row a centre and nothing ever moves.
//   So clusters are never empty and centres never equal.
//
// The result depends only on the rows and the seed, never on `threads`: the
// work is split into chunks, and every reduction over chunks is an exact
// integer sum.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace binbow::detail {

// Splitmix64: a tiny, fully specified generator, so that vocabularies are
// reproducible across standard libraries.
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, bound), bound > 0.
  std::uint64_t below(std::uint64_t bound);

 private:
  std::uint64_t state_;
};

// A well-mixed seed for child `index` of a node whose seed is `parent`.
std::uint64_t child_seed(std::uint64_t parent, std::uint64_t index);

class KMedians {
 public:
  KMedians(std::size_t code_size, std::uint32_t k);

  // Clusters `n` contiguous rows. assignment[i] receives the cluster of row i
  // and distance[i] its distance to that cluster's centre (both n elements).
  void cluster(const std::uint8_t* rows, std::size_t n, std::uint64_t seed, unsigned max_iterations,
               unsigned threads, std::uint32_t* assignment, std::uint32_t* distance);

  std::uint32_t cluster_count() const noexcept { return count_; }
  // cluster_count() × code_size bytes.
  const std::uint8_t* centres() const noexcept { return centres_.data(); }
  const std::uint8_t* centre(std::uint32_t c) const noexcept {
    return centres_.data() + c * code_size_;
  }
  std::uint32_t cluster_size(std::uint32_t c) const noexcept {
    return static_cast<std::uint32_t>(members_[c]);
  }
  // True when the last run stopped because no row moved (then every centre is
  // the majority of its members), false when it hit max_iterations.
  bool converged() const noexcept { return converged_; }
  unsigned iterations() const noexcept { return iterations_; }
  // Clusters re-seeded because they became empty, in the last run.
  std::size_t reseeded() const noexcept { return reseeded_; }

 private:
  struct Chunk {
    std::size_t begin = 0, end = 0;
    std::vector<std::int32_t> counts;   // k × bits
    std::vector<std::int32_t> members;  // k
    std::vector<std::uint8_t> dirty;    // k
    std::vector<std::uint64_t> packed;  // k × code_size, eight 8-bit counters each
    std::uint64_t squared_sum = 0;
    std::size_t moved = 0;
  };

  void cluster_distinct(const std::uint8_t* rows, std::size_t n, std::uint32_t* assignment,
                        std::uint32_t* distance);
  void seed_centres(std::uint64_t seed, std::uint32_t* assignment, std::uint32_t* distance);
  void count_bits(const std::uint32_t* assignment);
  bool update_centres();
  std::size_t assign(std::uint32_t* assignment, std::uint32_t* distance);
  std::size_t repair_empty_clusters(std::uint32_t* assignment, std::uint32_t* distance);
  void move_row(std::size_t row, std::uint32_t from, std::uint32_t to, std::int32_t* counts,
                std::int32_t* members, std::uint8_t* dirty) const;
  template <class Body>
  void for_chunks(Body&& body);

  std::size_t code_size_;
  std::size_t bits_;
  std::uint32_t k_;
  const std::uint8_t* rows_ = nullptr;
  std::size_t n_ = 0;
  unsigned threads_ = 1;
  std::uint32_t count_ = 0;
  std::vector<std::uint8_t> centres_;  // k × code_size
  std::vector<std::int32_t> counts_;   // k × bits: members having each bit set
  std::vector<std::int32_t> members_;  // k
  std::vector<std::uint8_t> dirty_;    // k: membership changed since the centre was set
  std::vector<std::uint32_t> scratch_index_, scratch_distance_;  // n
  std::vector<Chunk> chunks_;
  bool converged_ = false;
  unsigned iterations_ = 0;
  std::size_t reseeded_ = 0;
};

}  // namespace binbow::detail
