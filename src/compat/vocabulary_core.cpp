// TemplatedVocabulary's implementation over binbow::Vocabulary: words and
// nodes from binbow's descent, BoW values and scores in double precision
// with DBoW2's rules.
#include <cfloat>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "compat/core_impl.h"
#include "formats/loader.h"

namespace DBoW2 {
namespace binbow_detail {

void rethrow_naming(const std::string& filename) {
  try {
    throw;
  } catch (const binbow::Error& e) {
    const std::string message = e.what();
    if (message.find(filename) != std::string::npos) throw std::runtime_error(message);
    throw std::runtime_error(filename + ": " + message);
  }
}

namespace {

binbow::Weighting to_binbow(WeightingType weighting) {
  return binbow::weighting_from_code(static_cast<int>(weighting));
}
binbow::Scoring to_binbow(ScoringType scoring) {
  return binbow::scoring_from_code(static_cast<int>(scoring));
}

// DBoW2 stores whatever value it is given; one outside the enum would index
// past the names operator<< prints and reach transform() and score(), so it
// is refused where it is set. Compared as ints: an enum holding a value
// outside its range need not compare as one.
WeightingType checked(WeightingType weighting) {
  const int code = static_cast<int>(weighting);
  if (code < static_cast<int>(TF_IDF) || code > static_cast<int>(BINARY))
    throw std::invalid_argument("weighting type " + std::to_string(code) +
                                " is none of TF_IDF, TF, IDF, BINARY (0 to 3)");
  return weighting;
}
ScoringType checked(ScoringType scoring) {
  const int code = static_cast<int>(scoring);
  if (code < static_cast<int>(L1_NORM) || code > static_cast<int>(DOT_PRODUCT))
    throw std::invalid_argument(
        "scoring type " + std::to_string(code) +
        " is none of L1_NORM, L2_NORM, CHI_SQUARE, KL, BHATTACHARYYA, DOT_PRODUCT (0 to 5)");
  return scoring;
}

std::out_of_range no_word(WordId wid, std::size_t words) {
  return std::out_of_range("word " + std::to_string(wid) + " does not exist (the vocabulary has " +
                           std::to_string(words) + " words)");
}

}  // namespace

void VocabularyCore::Impl::assign(binbow::Vocabulary v) {
  k = static_cast<int>(v.branching());
  L = static_cast<int>(v.levels());
  weighting = static_cast<WeightingType>(v.weighting());
  scoring = static_cast<ScoringType>(v.scoring());
  parent.assign(v.node_count(), 0);
  for (binbow::NodeId node = 0; node < v.node_count(); ++node) {
    if (v.is_leaf(node)) continue;
    const binbow::NodeId first = v.first_child(node);
    for (binbow::NodeId child = first; child < first + v.child_count(node); ++child)
      parent[child] = node;
  }
  word_node = v.word_nodes();
  vocabulary = std::move(v);
}

binbow::Vocabulary VocabularyCore::Impl::current() const {
  if (vocabulary.empty()) return vocabulary;
  if (to_binbow(weighting) == vocabulary.weighting())
    return vocabulary.with_scoring(to_binbow(scoring));
  binbow::VocabularyTree tree = vocabulary.to_tree();
  tree.weighting = to_binbow(weighting);
  tree.scoring = to_binbow(scoring);
  return binbow::Vocabulary::from_tree(tree).with_descriptor(vocabulary.descriptor());
}

VocabularyCore::VocabularyCore(int k, int L, WeightingType weighting, ScoringType scoring)
    : impl_(new Impl) {
  impl_->k = k;
  impl_->L = L;
  impl_->weighting = checked(weighting);
  impl_->scoring = checked(scoring);
}

VocabularyCore::VocabularyCore(const VocabularyCore& other) : impl_(new Impl(*other.impl_)) {}

VocabularyCore& VocabularyCore::operator=(const VocabularyCore& other) {
  if (this != &other) impl_.reset(new Impl(*other.impl_));
  return *this;
}

VocabularyCore::~VocabularyCore() = default;

void VocabularyCore::create(const std::vector<std::vector<unsigned char> >& images,
                            std::size_t code_size, int k, int L, WeightingType weighting,
                            ScoringType scoring) {
  if (k < 2 || L < 1)
    throw std::invalid_argument("a vocabulary needs k >= 2 and L >= 1, not k = " +
                                std::to_string(k) + ", L = " + std::to_string(L));
  checked(weighting);
  checked(scoring);
  std::vector<binbow::DescriptorView> views;
  views.reserve(images.size());
  for (const auto& image : images)
    views.push_back({image.data(), code_size == 0 ? 0 : image.size() / code_size, code_size});
  binbow::BuildOptions options;
  options.branching = static_cast<std::uint32_t>(k);
  options.levels = static_cast<std::uint32_t>(L);
  options.weighting = to_binbow(weighting);
  options.scoring = to_binbow(scoring);
  try {
    impl_->assign(binbow::Vocabulary::build(views, options));
  } catch (const binbow::InvalidArgument& e) {
    throw std::invalid_argument(e.what());
  }
}

bool VocabularyCore::empty() const {
  return impl_->vocabulary.empty();
}
unsigned int VocabularyCore::size() const {
  return static_cast<unsigned int>(impl_->vocabulary.word_count());
}
std::size_t VocabularyCore::code_size() const {
  return impl_->vocabulary.code_size();
}
int VocabularyCore::branching() const {
  return impl_->k;
}
int VocabularyCore::levels() const {
  return impl_->L;
}
WeightingType VocabularyCore::weighting() const {
  return impl_->weighting;
}
ScoringType VocabularyCore::scoring() const {
  return impl_->scoring;
}
void VocabularyCore::set_weighting(WeightingType weighting) {
  impl_->weighting = checked(weighting);
}
void VocabularyCore::set_scoring(ScoringType scoring) {
  impl_->scoring = checked(scoring);
}

namespace {

void transform_features(const VocabularyCore::Impl& impl, const DescriptorBytes& features,
                        BowVector& v, FeatureVector* fv, int levelsup) {
  v.clear();
  if (fv) fv->clear();
  const binbow::Vocabulary& vocabulary = impl.vocabulary;
  if (vocabulary.empty() || features.count == 0) return;
  if (features.code_size != vocabulary.code_size())
    throw std::invalid_argument("descriptors of " + std::to_string(features.code_size) +
                                " bytes do not fit a vocabulary of " +
                                std::to_string(vocabulary.code_size()) + "-byte words");
  if (levelsup < 0)
    throw std::invalid_argument("levelsup must be at least 0, not " + std::to_string(levelsup));
  std::vector<binbow::WordId> words(features.count);
  std::vector<binbow::NodeId> nodes(fv ? features.count : 0);
  vocabulary.quantize({features.data, features.count, features.code_size}, words.data(),
                      fv ? nodes.data() : nullptr, static_cast<unsigned>(levelsup));
  // TF and TF-IDF add a word's weight per feature; IDF and BINARY set it once.
  const bool per_feature = impl.weighting == TF || impl.weighting == TF_IDF;
  for (std::size_t i = 0; i < words.size(); ++i) {
    const WordValue weight = vocabulary.word_weight(words[i]);
    if (!(weight > 0)) continue;  // a stop word: in neither vector
    if (per_feature)
      v.addWeight(words[i], weight);
    else
      v.addIfNotExist(words[i], weight);
    if (fv) fv->addFeature(nodes[i], static_cast<unsigned int>(i));
  }
  if (impl.scoring == DOT_PRODUCT) {
    if (per_feature && !v.empty()) {
      const double words_present = static_cast<double>(v.size());
      for (auto& entry : v) entry.second /= words_present;
    }
  } else {
    v.normalize(impl.scoring == L2_NORM ? L2 : L1);
  }
}

}  // namespace

void VocabularyCore::transform(const DescriptorBytes& features, BowVector& v) const {
  transform_features(*impl_, features, v, nullptr, 0);
}

void VocabularyCore::transform(const DescriptorBytes& features, BowVector& v, FeatureVector& fv,
                               int levelsup) const {
  transform_features(*impl_, features, v, &fv, levelsup);
}

WordId VocabularyCore::transform(const unsigned char* feature, std::size_t code_size) const {
  if (empty()) return 0;
  if (code_size != impl_->vocabulary.code_size())
    throw std::invalid_argument("a descriptor of " + std::to_string(code_size) +
                                " bytes does not fit a vocabulary of " +
                                std::to_string(impl_->vocabulary.code_size()) + "-byte words");
  return impl_->vocabulary.quantize(feature);
}

double VocabularyCore::score(const BowVector& a, const BowVector& b) const {
  // DBoW2's definitions, terms summed in increasing word order.
  static const double kLogEps = std::log(DBL_EPSILON);
  const ScoringType scoring = impl_->scoring;
  double sum = 0;
  BowVector::const_iterator ia = a.begin(), ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first == ib->first) {
      const double v = ia->second, w = ib->second;
      switch (scoring) {
        case L1_NORM:
          sum += std::fabs(v - w) - std::fabs(v) - std::fabs(w);
          break;
        case L2_NORM:
        case DOT_PRODUCT:
          sum += v * w;
          break;
        case CHI_SQUARE:
          if (v + w != 0.0) sum += v * w / (v + w);
          break;
        case KL:
          if (v != 0 && w != 0) sum += v * std::log(v / w);
          break;
        case BHATTACHARYYA:
          sum += std::sqrt(v * w);
          break;
      }
      ++ia;
      ++ib;
    } else if (ia->first < ib->first) {
      // KL charges a's words that b lacks as if b had them at DBL_EPSILON.
      if (scoring == KL) sum += ia->second * (std::log(ia->second) - kLogEps);
      ++ia;
    } else {
      ++ib;
    }
  }
  switch (scoring) {
    case L1_NORM:
      return -sum / 2.0;
    case L2_NORM:
      return sum >= 1 ? 1.0 : 1.0 - std::sqrt(1.0 - sum);
    case CHI_SQUARE:
      return 2. * sum;
    case KL:
      for (; ia != a.end(); ++ia)
        if (ia->second != 0) sum += ia->second * (std::log(ia->second) - kLogEps);
      return sum;
    case BHATTACHARYYA:
    case DOT_PRODUCT:
      return sum;
  }
  return sum;
}

NodeId VocabularyCore::parent_node(WordId wid, int levelsup) const {
  if (wid >= impl_->word_node.size()) throw no_word(wid, impl_->word_node.size());
  NodeId node = impl_->word_node[wid];
  for (; levelsup > 0 && node != 0; --levelsup) node = impl_->parent[node];
  return node;
}

void VocabularyCore::words_from_node(NodeId nid, std::vector<WordId>& words) const {
  words.clear();
  const binbow::Vocabulary& vocabulary = impl_->vocabulary;
  if (nid >= vocabulary.node_count())
    throw std::out_of_range("node " + std::to_string(nid) + " does not exist (the vocabulary has " +
                            std::to_string(vocabulary.node_count()) + " nodes)");
  if (vocabulary.is_leaf(nid)) {
    words.push_back(vocabulary.node_word(nid));
    return;
  }
  // DBoW2's order: depth-first from a stack of inner nodes, leaves listed as
  // their parent is expanded.
  std::vector<NodeId> inner(1, nid);
  while (!inner.empty()) {
    const NodeId node = inner.back();
    inner.pop_back();
    const NodeId first = vocabulary.first_child(node);
    for (NodeId child = first; child < first + vocabulary.child_count(node); ++child) {
      if (vocabulary.is_leaf(child))
        words.push_back(vocabulary.node_word(child));
      else
        inner.push_back(child);
    }
  }
}

float VocabularyCore::effective_levels() const {
  long sum = 0;
  for (NodeId node : impl_->word_node)
    for (; node != 0; node = impl_->parent[node]) ++sum;
  return static_cast<float>(static_cast<double>(sum) /
                            static_cast<double>(impl_->word_node.size()));
}

const unsigned char* VocabularyCore::word_descriptor(WordId wid) const {
  if (wid >= impl_->word_node.size()) throw no_word(wid, impl_->word_node.size());
  return impl_->vocabulary.node_descriptor(impl_->word_node[wid]);
}

WordValue VocabularyCore::word_weight(WordId wid) const {
  if (wid >= impl_->word_node.size()) throw no_word(wid, impl_->word_node.size());
  return impl_->vocabulary.word_weight(wid);
}

int VocabularyCore::stop_words(double min_weight) {
  if (empty()) return 0;
  binbow::VocabularyTree tree = impl_->vocabulary.to_tree();
  int stopped = 0;
  for (NodeId node : impl_->word_node)
    if (tree.weights[node] < min_weight) {
      tree.weights[node] = 0;
      ++stopped;
    }
  if (stopped > 0) {
    const Impl kept = *impl_;
    impl_->assign(
        binbow::Vocabulary::from_tree(tree).with_descriptor(kept.vocabulary.descriptor()));
    impl_->weighting = kept.weighting;
    impl_->scoring = kept.scoring;
  }
  return stopped;
}

// DBoW2's API never extracts features, so the extractor a file does not
// record is left unnamed, without the warning binbow's own loading gives;
// ORB-SLAM's loaders read ORB-SLAM's ORB vocabularies.
void VocabularyCore::load(const std::string& filename) {
  try {
    impl_->assign(binbow::detail::load_vocabulary_with_details(
                      filename, binbow::VocabularyFormat::kAuto, "",
                      binbow::detail::UnrecordedDescriptor::kLeaveBlank)
                      .vocabulary);
  } catch (...) {
    rethrow_naming(filename);
  }
}

void VocabularyCore::save(const std::string& filename, bool bit_strings) const {
  try {
    if (empty()) throw binbow::FileError(filename, "the vocabulary is empty: nothing to save");
    binbow::save_vocabulary(impl_->current(), filename, binbow::VocabularyFormat::kAuto,
                            bit_strings);
  } catch (...) {
    rethrow_naming(filename);
  }
}

bool VocabularyCore::load_orbslam(const std::string& filename, bool binary) {
  try {
    impl_->assign(binbow::load_vocabulary(
        filename,
        binary ? binbow::VocabularyFormat::kOrbSlamBinary : binbow::VocabularyFormat::kOrbSlamText,
        "orb"));
    return true;
  } catch (const binbow::Error&) {
    return false;
  }
}

void VocabularyCore::save_orbslam(const std::string& filename, bool binary) const {
  try {
    if (empty()) throw binbow::FileError(filename, "the vocabulary is empty: nothing to save");
    binbow::save_vocabulary(
        impl_->current(), filename,
        binary ? binbow::VocabularyFormat::kOrbSlamBinary : binbow::VocabularyFormat::kOrbSlamText);
  } catch (...) {
    rethrow_naming(filename);
  }
}

}  // namespace binbow_detail
}  // namespace DBoW2
