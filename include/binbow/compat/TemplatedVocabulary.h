// DBoW2 compatibility layer: DBoW2's TemplatedVocabulary over binbow's vocabulary.
//
// C++11; includes the standard library and OpenCV core only (see DBoW2.h).
// Behaviour follows DBoW2's code: transform() adds each feature's word weight
// (TF, TF_IDF) or sets it once (IDF, BINARY), leaves out features whose word
// weighs 0 (from both vectors), then normalises as the scoring type requires
// (L1 for L1_NORM, CHI_SQUARE, KL, BHATTACHARYYA; L2 for L2_NORM; DOT_PRODUCT
// divides TF and TF_IDF values by the number of words instead). Words, nodes
// and BoW values come from binbow's descent, which equals DBoW2's; values and
// scores are computed in double precision from the word weights, which binbow
// keeps in single precision (vocabulary files with double weights agree with
// DBoW2 to about 1e-7 relative).
#ifndef BINBOW_COMPAT_DBOW2_TEMPLATED_VOCABULARY_H
#define BINBOW_COMPAT_DBOW2_TEMPLATED_VOCABULARY_H

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

#include "binbow/compat/BowVector.h"
#include "binbow/compat/FBrief.h"
#include "binbow/compat/FORB.h"
#include "binbow/compat/FeatureVector.h"
#include "binbow/compat/detail/core.h"
#include "binbow/compat/detail/descriptor_bytes.h"

namespace DBoW2 {

template <class TDescriptor, class F>
class TemplatedDatabase;

/// A vocabulary tree of k branches and L levels whose leaves are the words.
/// TDescriptor/F: FORB::TDescriptor/FORB (ORB, cv::Mat rows of 32 bytes) or
/// FBrief::TDescriptor/FBrief (BRIEF, std::bitset<256>); any F with the same
/// descriptor types works, since binbow compares descriptors itself
/// (Hamming distance, lowest child index on ties, as DBoW2's FORB/FBrief).
///
/// create(), transform() (and TemplatedDatabase's add() and query()) also
/// take descriptors of the other types binbow knows: cv::Mat rows of CV_8U
/// bytes, std::bitset<N>, and boost::dynamic_bitset<> or any bitset type with
/// size() and test(i); bit i of a bitset is bit i % 8 of byte i / 8 of the
/// row (FBrief.h), so the same bits give the same words in every type.
///
/// Errors: loading and saving throw std::runtime_error whose message names
/// the file; descriptors of another size than the vocabulary's, and
/// weighting or scoring types outside their enums, throw
/// std::invalid_argument; word ids out of range throw std::out_of_range.
template <class TDescriptor, class F>
class TemplatedVocabulary {
 public:
  /// An empty vocabulary that create() will build with these parameters.
  TemplatedVocabulary(int k = 10, int L = 5, WeightingType weighting = TF_IDF,
                      ScoringType scoring = L1_NORM)
      : core_(k, L, weighting, scoring) {}
  /// Loads a vocabulary file in any format binbow reads (see load()).
  TemplatedVocabulary(const std::string& filename) : core_(10, 5, TF_IDF, L1_NORM) {
    load(filename);
  }
  TemplatedVocabulary(const char* filename) : core_(10, 5, TF_IDF, L1_NORM) {
    load(std::string(filename));
  }
  virtual ~TemplatedVocabulary() {}

  /// Builds the tree with binbow's hierarchical k-medians (deterministic;
  /// not DBoW2's randomised k-means++, so the words differ from those DBoW2
  /// would make) and sets the word weights from the training images.
  /// Throws std::invalid_argument for unusable input (e.g. IDF weights from
  /// fewer than two images, k outside 2..255, L outside 1..16).
  virtual void create(const std::vector<std::vector<TDescriptor> >& training_features) {
    create_from(training_features, core_.branching(), core_.levels(), core_.weighting(),
                core_.scoring());
  }
  virtual void create(const std::vector<std::vector<TDescriptor> >& training_features, int k,
                      int L) {
    create_from(training_features, k, L, core_.weighting(), core_.scoring());
  }
  virtual void create(const std::vector<std::vector<TDescriptor> >& training_features, int k, int L,
                      WeightingType weighting, ScoringType scoring) {
    create_from(training_features, k, L, weighting, scoring);
  }
  /// The same from descriptors of another type (see the class comment).
  template <class D>
  typename binbow_detail::if_descriptor<D>::type create(
      const std::vector<std::vector<D> >& training_features) {
    create_from(training_features, core_.branching(), core_.levels(), core_.weighting(),
                core_.scoring());
  }
  template <class D>
  typename binbow_detail::if_descriptor<D>::type create(
      const std::vector<std::vector<D> >& training_features, int k, int L) {
    create_from(training_features, k, L, core_.weighting(), core_.scoring());
  }
  template <class D>
  typename binbow_detail::if_descriptor<D>::type create(
      const std::vector<std::vector<D> >& training_features, int k, int L, WeightingType weighting,
      ScoringType scoring) {
    create_from(training_features, k, L, weighting, scoring);
  }

  /// Number of words.
  virtual unsigned int size() const { return core_.size(); }
  virtual bool empty() const { return core_.empty(); }

  /// BoW vector of an image's features (cleared first; left empty by an
  /// empty vocabulary).
  virtual void transform(const std::vector<TDescriptor>& features, BowVector& v) const {
    transform_from(features, v);
  }
  /// The same for descriptors of another type (see the class comment).
  template <class D>
  typename binbow_detail::if_descriptor<D>::type transform(const std::vector<D>& features,
                                                           BowVector& v) const {
    transform_from(features, v);
  }
  /// Also the feature vector: each kept feature under its word's ancestor at
  /// depth L - levelsup from the root (the root when levelsup >= L; the leaf
  /// itself when the leaf is shallower, where DBoW2 leaves the node
  /// undefined). Note that getParentNode(word, levelsup) counts from the leaf
  /// instead: the two differ for leaves shallower than L.
  virtual void transform(const std::vector<TDescriptor>& features, BowVector& v, FeatureVector& fv,
                         int levelsup) const {
    transform_from(features, v, fv, levelsup);
  }
  template <class D>
  typename binbow_detail::if_descriptor<D>::type transform(const std::vector<D>& features,
                                                           BowVector& v, FeatureVector& fv,
                                                           int levelsup) const {
    transform_from(features, v, fv, levelsup);
  }
  /// The word of one descriptor (0 for an empty vocabulary).
  virtual WordId transform(const TDescriptor& feature) const { return word_of(feature); }
  template <class D>
  typename binbow_detail::if_descriptor<D, WordId>::type transform(const D& feature) const {
    return word_of(feature);
  }

  /// Similarity of two BoW vectors under the scoring type (DBoW2's
  /// formulas; KL is a divergence: lower is more similar).
  double score(const BowVector& a, const BowVector& b) const { return core_.score(a, b); }

  /// The node `levelsup` steps above word `wid`'s leaf, stopping at the root.
  virtual NodeId getParentNode(WordId wid, int levelsup) const {
    return core_.parent_node(wid, levelsup);
  }
  /// The words under node `nid` (the word itself for a leaf).
  void getWordsFromNode(NodeId nid, std::vector<WordId>& words) const {
    core_.words_from_node(nid, words);
  }

  int getBranchingFactor() const { return core_.branching(); }
  int getDepthLevels() const { return core_.levels(); }
  /// Mean depth of the words.
  float getEffectiveLevels() const { return core_.effective_levels(); }

  /// The descriptor of word `wid` (its cluster centre).
  virtual TDescriptor getWord(WordId wid) const {
    TDescriptor d;
    binbow_detail::descriptor_from_bytes(core_.word_descriptor(wid), core_.code_size(), d);
    return d;
  }
  virtual WordValue getWordWeight(WordId wid) const { return core_.word_weight(wid); }

  WeightingType getWeightingType() const { return core_.weighting(); }
  ScoringType getScoringType() const { return core_.scoring(); }
  /// Changes how transform() weighs words; the word weights themselves stay.
  /// A value outside the enum throws std::invalid_argument and changes nothing.
  void setWeightingType(WeightingType type) { core_.set_weighting(type); }
  /// Throws std::invalid_argument for a value outside the enum, as above.
  void setScoringType(ScoringType type) { core_.set_scoring(type); }

  /// Writes the vocabulary in the format its extension names: .yml, .yaml,
  /// .yml.gz, .voc.gz (DBoW2 YAML as DBoW2's save writes it: decimal bytes
  /// for FORB, bit strings for FBrief), .txt (ORB-SLAM
  /// text), .bin (ORB-SLAM binary), .bbw (binbow), .dbow3, .fbow; any may
  /// end in .gz. Atomic: a failed save leaves no partial file.
  void save(const std::string& filename) const {
    core_.save(filename, binbow_detail::yaml_bit_strings(static_cast<const F*>(NULL)));
  }
  /// Reads a vocabulary in any format binbow reads, detected from the
  /// content: DBoW2 YAML (plain or gzip), ORB-SLAM text and binary,
  /// binbow .bbw, DBoW3, fbow, VINS binary. Replaces k, L, the weighting and
  /// scoring types and the words.
  void load(const std::string& filename) { core_.load(filename); }

  /// ORB-SLAM2/3's text vocabulary (ORBvoc.txt): false when the file cannot
  /// be read as one (the vocabulary is then unchanged).
  bool loadFromTextFile(const std::string& filename) { return core_.load_orbslam(filename, false); }
  void saveToTextFile(const std::string& filename) const { core_.save_orbslam(filename, false); }
  /// The binary ORBvoc.bin of ORB-SLAM forks: false when unreadable.
  bool loadFromBinaryFile(const std::string& filename) {
    return core_.load_orbslam(filename, true);
  }
  void saveToBinaryFile(const std::string& filename) const { core_.save_orbslam(filename, true); }
  /// VINS-Mono/Fusion's binary vocabulary: read through format detection,
  /// as load() does.
  void loadBin(const std::string& filename) { core_.load(filename); }

  /// Sets to 0 the weight of every word weighing less than `minWeight`
  /// (such words are then left out of BoW and feature vectors) and returns
  /// how many words that was (including words already at 0).
  virtual int stopWords(double minWeight) { return core_.stop_words(minWeight); }

 private:
  template <class, class>
  friend class TemplatedDatabase;

  template <class D>
  void create_from(const std::vector<std::vector<D> >& training_features, int k, int L,
                   WeightingType weighting, ScoringType scoring) {
    std::vector<std::vector<unsigned char> > images(training_features.size());
    const std::size_t bytes = training_code_size(training_features);
    for (std::size_t i = 0; i < training_features.size(); ++i)
      for (std::size_t j = 0; j < training_features[i].size(); ++j)
        binbow_detail::append_descriptor_bytes(training_features[i][j], bytes, images[i]);
    core_.create(images, bytes, k, L, weighting, scoring);
  }

  template <class D>
  static std::size_t training_code_size(const std::vector<std::vector<D> >& training_features) {
    for (std::size_t i = 0; i < training_features.size(); ++i)
      if (!training_features[i].empty()) {
        std::vector<unsigned char> first;
        binbow_detail::append_descriptor_bytes(training_features[i][0], 0, first);
        return first.size();
      }
    return 0;
  }

  template <class D>
  void transform_from(const std::vector<D>& features, BowVector& v) const {
    std::vector<unsigned char> bytes;
    core_.transform(to_bytes(features, bytes), v);
  }
  template <class D>
  void transform_from(const std::vector<D>& features, BowVector& v, FeatureVector& fv,
                      int levelsup) const {
    std::vector<unsigned char> bytes;
    core_.transform(to_bytes(features, bytes), v, fv, levelsup);
  }
  template <class D>
  WordId word_of(const D& feature) const {
    if (empty()) return 0;
    std::vector<unsigned char> bytes;
    binbow_detail::append_descriptor_bytes(feature, core_.code_size(), bytes);
    return core_.transform(bytes.data(), bytes.size());
  }

  template <class D>
  binbow_detail::DescriptorBytes to_bytes(const std::vector<D>& features,
                                          std::vector<unsigned char>& bytes) const {
    const std::size_t code_size = core_.code_size();
    if (!empty()) {
      bytes.reserve(features.size() * code_size);
      for (std::size_t i = 0; i < features.size(); ++i)
        binbow_detail::append_descriptor_bytes(features[i], code_size, bytes);
    }
    binbow_detail::DescriptorBytes view = {bytes.data(), empty() ? 0 : features.size(), code_size};
    return view;
  }

  binbow_detail::VocabularyCore core_;
};

/// "Vocabulary: k = 10, L = 6, Weighting = tf-idf, Scoring = L1-norm,
/// Number of words = 1000000", as DBoW2 prints it.
template <class TDescriptor, class F>
std::ostream& operator<<(std::ostream& os, const TemplatedVocabulary<TDescriptor, F>& voc) {
  static const char* const weightings[] = {"tf-idf", "tf", "idf", "binary"};
  static const char* const scorings[] = {
      "L1-norm",    "L2-norm", "Chi square distance", "KL-divergence", "Bhattacharyya coefficient",
      "Dot product"};
  os << "Vocabulary: k = " << voc.getBranchingFactor() << ", L = " << voc.getDepthLevels()
     << ", Weighting = " << weightings[voc.getWeightingType()]
     << ", Scoring = " << scorings[voc.getScoringType()] << ", Number of words = " << voc.size();
  return os;
}

}  // namespace DBoW2

#endif
