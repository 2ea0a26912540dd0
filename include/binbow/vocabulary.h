// The vocabulary tree: k-branch, L-level hierarchy of binary cluster centres
// whose leaves are the words (Nistér & Stewénius; Gálvez-López & Tardós).
//
// Memory layout (fbow-like): the whole tree lives in one immutable block —
// node descriptors in one contiguous array, the children of every node stored
// next to each other, plus a link per node and a weight per word. Node ids and
// word ids follow DBoW2's order (depth-first creation order, children
// allocated together; words numbered as leaves appear), so ids coincide with
// those of the DBoW2 or ORB-SLAM file a vocabulary was read from.
//
// A Vocabulary is immutable after construction and cheap to copy (the block is
// shared); every const method is safe to call from any number of threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/descriptors.h"
#include "binbow/types.h"

namespace binbow {

class Vocabulary;
namespace detail {
struct VocabularyBlock;
// The weight of every word, for the database's per-posting work (null for
// an empty vocabulary).
const float* word_weights(const Vocabulary& vocabulary) noexcept;
}  // namespace detail

// A vocabulary as a plain tree: the interchange form between builders, file
// readers and writers, and the flat Vocabulary. Node 0 is the root.
struct VocabularyTree {
  std::size_t code_size = 0;    // bytes per descriptor
  std::uint32_t branching = 0;  // k: maximum children per node (1..255)
  std::uint32_t levels = 0;     // L: maximum depth of a leaf (root has depth 0)
  Weighting weighting = Weighting::kTfIdf;
  Scoring scoring = Scoring::kL1;
  std::vector<NodeId> parent;             // parent[i] for i ≥ 1; parent[0] is ignored
  std::vector<std::uint8_t> descriptors;  // node_count() × code_size; the root's bytes are ignored
  std::vector<float> weights;             // per node; only leaves' (the words') weights are kept
  // The feature extractor whose descriptors trained the tree ("orb", "brief",
  // ...): at most 8 characters of a-z, 0-9, '_' and '-'; empty when unknown.
  // Stored in .bbw files only, so that tools can refuse descriptors of
  // another kind with the same length (ORB and BRIEF are both 256-bit).
  std::string descriptor;

  std::size_t node_count() const noexcept { return parent.size(); }
};

// Progress of Vocabulary::build, reported from the calling thread.
struct BuildProgress {
  std::size_t clustered_descriptors = 0;  // descriptors that reached a leaf so far
  std::size_t total_descriptors = 0;
  std::size_t nodes = 0;  // nodes created so far
};

struct BuildOptions {
  std::uint32_t branching = 10;  // k
  std::uint32_t levels = 6;      // L
  Weighting weighting = Weighting::kTfIdf;
  Scoring scoring = Scoring::kL1;
  std::uint64_t seed = 0;        // same seed and data ⇒ same vocabulary, whatever `threads`
  unsigned threads = 0;          // 0: all hardware threads
  unsigned max_iterations = 20;  // k-medians iterations per node, stops earlier on convergence
  // Words present in more than this fraction of training images get weight 0
  // (stop words; they then contribute nothing to BoW vectors). 1 disables.
  double stop_word_fraction = 1.0;
  std::string descriptor;  // recorded in the vocabulary (see VocabularyTree::descriptor)
  std::function<void(const BuildProgress&)> progress;  // optional, called now and then
};

struct LoadOptions {
  // Verify the CRC of every section. Structural checks (that no link leaves
  // the tree) are always done, so skipping this cannot make later calls crash;
  // it only trades corruption detection in descriptors and weights for speed.
  bool verify_checksums = true;
};

class Vocabulary {
 public:
  // An empty vocabulary (no nodes); transform() on it throws.
  Vocabulary();

  // Hierarchical k-medians over training descriptors, one view per training
  // image (the images define the IDF weights: idf = log(N / N_i), N images,
  // N_i of them containing word i). Throws InvalidArgument on empty input,
  // mixed code sizes, branching outside 2..255 or levels outside 1..16, and
  // when every word would weigh 0 (every BoW vector empty): IDF weighting of
  // fewer than two images, or of images all sharing every word, or every word
  // a stop word.
  static Vocabulary build(const std::vector<DescriptorView>& images, const BuildOptions& options);

  // From a plain tree. Validates it (parents in range, no cycle or unreachable
  // node, depth ≤ levels, at most `branching` children) and renumbers nodes to
  // DBoW2's depth-first order (the identity for trees written by DBoW2).
  // Throws InvalidArgument naming the first problem found.
  static Vocabulary from_tree(const VocabularyTree& tree);
  VocabularyTree to_tree() const;

  // binbow's own format (.bbw): memory-mapped, validated. Throws FileError.
  static Vocabulary load(const std::string& path, const LoadOptions& options = {});
  // Atomic: writes "<path>.tmp-XXXX" then renames; missing folders are made.
  // Throws FileError.
  void save(const std::string& path) const;
  // The exact bytes save() writes.
  std::vector<std::uint8_t> serialize() const;
  // Parses bytes produced by serialize(); `name` is used in error messages.
  static Vocabulary deserialize(const std::uint8_t* data, std::size_t size, const std::string& name,
                                const LoadOptions& options = {});

  bool empty() const noexcept;
  std::size_t code_size() const noexcept;
  std::uint32_t branching() const noexcept;
  std::uint32_t levels() const noexcept;
  Weighting weighting() const noexcept;
  Scoring scoring() const noexcept;
  std::size_t node_count() const noexcept;
  std::size_t word_count() const noexcept;
  // CRC32C of the vocabulary's content (tree, weights, types): two vocabularies
  // with equal checksums describe the same words. Databases store it.
  std::uint32_t checksum() const noexcept;
  // The extractor that trained it ("orb", "brief", ...) or "" when unknown
  // (files of other formats do not record it). Not part of checksum().
  const std::string& descriptor() const noexcept;
  // "k=10 L=6 tf-idf l1, 24830 words, 56062 nodes, 256-bit descriptors"
  std::string description() const;

  // Node access (ids < node_count()).
  const std::uint8_t* node_descriptor(NodeId node) const;
  bool is_leaf(NodeId node) const;
  NodeId first_child(NodeId node) const;         // meaningful for inner nodes
  std::uint32_t child_count(NodeId node) const;  // 0 for leaves
  WordId node_word(NodeId node) const;           // meaningful for leaves
  float word_weight(WordId word) const;
  // Leaf node of every word, computed on demand (O(nodes)).
  std::vector<NodeId> word_nodes() const;

  // The word of one descriptor (greedy descent: nearest child by Hamming
  // distance at every level, lowest index on ties, as DBoW2).
  WordId quantize(const std::uint8_t* descriptor) const;
  // Words of many descriptors; `words` holds descriptors.rows elements.
  // When `nodes` is not null, nodes[i] receives the node at depth
  // max(levels() − levels_up, 0) on descriptor i's path (the leaf itself if
  // the leaf is shallower) — DBoW2's direct-index node.
  void quantize(const DescriptorView& descriptors, WordId* words, NodeId* nodes = nullptr,
                unsigned levels_up = 0) const;

  // Mean Hamming distance in bits from each descriptor to the descriptor of
  // its word (greedy descent): how closely the vocabulary fits these
  // descriptors, lower is better; 0 for no descriptors.
  double mean_quantisation_error(const DescriptorView& descriptors) const;

  // Descriptors → BoW vector, weighted and normalised as DBoW2's
  // transform(features, v). Throws InvalidArgument if the code size differs.
  void transform(const DescriptorView& descriptors, BowVector& bow) const;
  // Also fills the feature vector (direct index) at `levels_up` levels above
  // the leaves, as DBoW2's transform(features, v, fv, levelsup).
  void transform(const DescriptorView& descriptors, BowVector& bow, FeatureVector& features,
                 unsigned levels_up) const;

  // Similarity of two BoW vectors made by this vocabulary, with its scoring
  // type (DBoW2's definitions; see Scoring).
  double score(const BowVector& a, const BowVector& b) const;

  // A copy that scores (and normalises) with another type; shares the tree.
  Vocabulary with_scoring(Scoring scoring) const;
  // A copy that records another extractor (see VocabularyTree::descriptor;
  // "" for unknown), e.g. for a vocabulary read from a format that cannot
  // record it. Same checksum. Throws InvalidArgument for a name that breaks
  // the rule of VocabularyTree::descriptor, or on an empty vocabulary.
  Vocabulary with_descriptor(const std::string& descriptor) const;

 private:
  friend const float* detail::word_weights(const Vocabulary& vocabulary) noexcept;
  explicit Vocabulary(std::shared_ptr<const detail::VocabularyBlock> block);
  void words_to_bow(const WordId* words, std::size_t count, BowVector& bow) const;
  std::shared_ptr<const detail::VocabularyBlock> block_;
  Scoring scoring_ = Scoring::kL1;
};

// Similarity of two BoW vectors under `scoring` (vectors must already be
// normalised as that scoring requires: Vocabulary::transform does it).
double score_bow(const BowVector& a, const BowVector& b, Scoring scoring);

}  // namespace binbow
