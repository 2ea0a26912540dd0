// An online vocabulary: binary words that grow from the images' own
// descriptors, for place recognition without a pre-trained vocabulary (the
// idea of iBoW-LCD, Garcia-Fidalgo & Ortiz, RA-L 2018; no code taken).
//
// Words. Every descriptor of an added image goes to its nearest word. When
// that word is farther than OnlineVocabularyOptions::new_word_distance (or
// there is none), the descriptor becomes a new word; otherwise it joins the
// word, whose descriptor becomes the bitwise majority of the descriptors it
// has represented (per-bit counters; a tie keeps the bit, so a word never
// flips on one disagreeing descriptor). Descriptors are taken in row order
// and may join words made by earlier rows of the same image.
//
// Ids. Word ids are dense in creation order (0, 1, 2, ...) and never reused.
// A word seen in a single image is purged once `purge_after_images` further
// images have been added without it; add_image() reports the purged ids, so
// an index holding postings for them can drop them. Every other word lives as
// long as the vocabulary.
//
// Search. The nearest word is found in several randomised hierarchical
// clustering trees of words (Muja & Lowe, 2012): each inner node splits its
// words around `branching` centres drawn at random among them; a new word
// descends each tree to the leaf of its nearest centres, and a leaf holding
// more than `leaf_size` words splits. Every tree is rebuilt from scratch once
// the vocabulary has doubled since its last build (amortised O(log n) per
// word), which keeps the trees balanced as the words grow. A search descends
// every tree, then explores the closest unexplored branches of all trees
// until it has compared `max_checks` words (Muja & Lowe's priority search), so
// its cost does not grow with the vocabulary; it is approximate. `exact`
// compares every word instead (for tests and small vocabularies).
//
// Weights. IDF comes from the images added so far: idf_i = log(N / n_i), N
// images, n_i of them containing word i; a word in every image weighs 0 (a
// stop word, dropped from BoW vectors as Vocabulary does). transform() makes
// TF-IDF BoW vectors normalised as Vocabulary::transform does (L1 for
// Scoring::kL1), and a FeatureVector whose node is the word itself.
//
// Determinism: the same images in the same order, with the same options,
// give the same words, ids, purges and vectors, on any machine.
//
// Not thread-safe for writers: add_image() needs exclusive access; the const
// methods may run concurrently with each other.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/descriptors.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"

namespace binbow {

struct OnlineVocabularyOptions {
  // A descriptor farther than this from its nearest word becomes a new word,
  // as a fraction of the descriptor's bits (0.25 of 256 bits: 64 bits), in
  // [0, 1]. See docs/online-vocabulary.md for the measurements behind it
  // (loop detection recall with ORB and BRIEF chose it).
  double new_word_distance = 0.25;
  // A word seen in a single image is purged when this many further images
  // have been added (0: never purge). [0, 2^31)
  std::uint32_t purge_after_images = 50;
  // Search trees: their number [1, 16], branching factor [2, 64] and the
  // number of words a leaf holds before it splits [1, 4096]. Big leaves (256,
  // not 64) spend the search on words rather than on centres: the loop
  // detector's time per frame drops by a sixth at the same recall
  // (docs/online-vocabulary.md).
  std::uint32_t trees = 4;
  std::uint32_t branching = 16;
  std::uint32_t leaf_size = 256;
  // Words compared per search at most, beyond the first descent of every
  // tree [1, 2^31). More: closer to exact, slower.
  std::uint32_t max_checks = 256;
  // Compare every word: exact nearest word (lowest id on equal distances).
  bool exact = false;
  // How transform() normalises BoW vectors (Database scores with it).
  Scoring scoring = Scoring::kL1;
  // The extractor of the descriptors ("orb", "brief", ...; the rule of
  // VocabularyTree::descriptor), recorded in saved states and exports.
  std::string descriptor;
  std::uint64_t seed = 0;  // the trees' random centres
};

// What add_image() did to the vocabulary.
struct OnlineImageWords {
  std::vector<WordId> words;   // the word of every descriptor, in row order
  std::vector<WordId> purged;  // words removed by this call, increasing
  std::size_t new_words = 0;   // words created by this call
};

// Counters of an OnlineVocabulary.
struct OnlineVocabularyStats {
  std::size_t images = 0;        // images added
  std::size_t words = 0;         // live words
  WordId next_word_id = 0;       // ids ever created
  std::size_t purged_words = 0;  // words purged so far
  std::size_t tree_rebuilds = 0;
  std::size_t memory_bytes = 0;  // heap memory held (words, counters, trees)
};

// A word and what the vocabulary knows of it.
struct OnlineWordInfo {
  WordId id = 0;
  std::uint32_t images = 0;        // n_i: images containing the word
  std::uint32_t observations = 0;  // descriptors it has represented
  std::uint32_t first_image = 0;   // index of the image that created it
  std::uint32_t last_image = 0;    // index of the last image containing it
};

class OnlineVocabulary {
 public:
  // An empty vocabulary for descriptors of `code_size` bytes (1..1024).
  // Throws InvalidArgument naming an option out of range.
  explicit OnlineVocabulary(std::size_t code_size, OnlineVocabularyOptions options = {});
  OnlineVocabulary(const OnlineVocabulary& other);
  OnlineVocabulary& operator=(const OnlineVocabulary& other);
  OnlineVocabulary(OnlineVocabulary&&) noexcept;
  OnlineVocabulary& operator=(OnlineVocabulary&&) noexcept;
  ~OnlineVocabulary();

  // Adds one image: assigns (and creates) the words of its descriptors, then
  // purges the words that have expired. Throws InvalidArgument if the code
  // size differs, after 2^32 - 1 images, or when the image has more
  // descriptors than word ids are left (2^32 - 1 ids in all); the vocabulary
  // is unchanged then. The second form reuses the capacity of `result`.
  OnlineImageWords add_image(const DescriptorView& descriptors);
  void add_image(const DescriptorView& descriptors, OnlineImageWords& result);

  // The nearest word of every descriptor and its Hamming distance (the
  // vocabulary's search: approximate unless options().exact), without
  // changing anything. kNoWord (distance kNoWord too) when there are no
  // words. Throws InvalidArgument if the code size differs.
  static constexpr WordId kNoWord = 0xFFFFFFFFu;
  void nearest_words(const DescriptorView& descriptors, WordId* words,
                     std::uint32_t* distances) const;

  // Query side, the vocabulary unchanged: each descriptor's nearest word, or
  // none when it is farther than new_word_distance (it would be a new word,
  // which no image contains); TF-IDF weighted, normalised for
  // options().scoring. With `features`, also the direct index, node = word.
  void transform(const DescriptorView& descriptors, BowVector& bow,
                 FeatureVector* features = nullptr) const;
  // The same from words already found (e.g. OnlineImageWords::words of the
  // image just added, so that it needs no second search). kNoWord and purged
  // words are skipped.
  void weigh(const WordId* words, std::size_t count, BowVector& bow,
             FeatureVector* features = nullptr) const;

  std::size_t code_size() const noexcept;
  const OnlineVocabularyOptions& options() const noexcept;
  OnlineVocabularyStats stats() const;
  std::size_t word_count() const noexcept;   // live words
  std::size_t image_count() const noexcept;  // images added
  WordId next_word_id() const noexcept;      // ids ever created
  bool contains(WordId word) const noexcept;
  // Throw InvalidArgument for a word that does not exist (never created or
  // purged).
  const std::uint8_t* word_descriptor(WordId word) const;
  OnlineWordInfo word_info(WordId word) const;
  // log(N / n_i) with the images added so far.
  double idf(WordId word) const;
  // Live word ids, increasing.
  std::vector<WordId> words() const;

  // The state as a file (.bbov: magic, version, little-endian sections with a
  // CRC32C each, see docs/online-vocabulary.md), written atomically (missing
  // folders are made).
  // Restoring gives the same words, counters, options and search trees (their
  // nodes, centres and leaves in order, and the random draws to come), so a
  // restored vocabulary searches and grows exactly as the saved one would
  // have, approximate search included. A version-1 file (no trees, written
  // before binbow kept them) still loads with its trees rebuilt from the
  // words: it continues the same way from every load, and exactly as the
  // saved vocabulary only with `exact`. Throws FileError.
  void save(const std::string& path) const;
  static OnlineVocabulary load(const std::string& path);
  std::vector<std::uint8_t> serialize() const;
  // `name` stands for the path in error messages (FileError).
  static OnlineVocabulary deserialize(const std::uint8_t* data, std::size_t size,
                                      const std::string& name);

  // A fixed vocabulary from the live words: a k-medians tree over the words
  // (Vocabulary::build with options' branching, levels, seed, threads), each
  // leaf weighted log(N / n) with n the images containing its words (their
  // n_i summed, at most N: exact when the words of a leaf never share an
  // image), so that later runs can use a .bbw. options.weighting must be
  // tf-idf or idf; options.descriptor, if empty, becomes this vocabulary's.
  // Throws InvalidArgument when there are fewer than two words or no word
  // has a positive weight.
  Vocabulary to_vocabulary(const BuildOptions& options) const;

 private:
  struct Impl;
  explicit OnlineVocabulary(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace binbow
