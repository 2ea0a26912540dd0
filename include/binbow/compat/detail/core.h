// DBoW2 compatibility layer: the non-templated classes that the templates in
// TemplatedVocabulary.h and TemplatedDatabase.h forward to. They are compiled
// inside binbow (C++17, over binbow::Vocabulary and binbow::Database) and
// exchange only standard types, DBoW2's map-based vectors and descriptor
// bytes, so this header stays C++11. Not meant to be used directly.
#ifndef BINBOW_COMPAT_DBOW2_DETAIL_CORE_H
#define BINBOW_COMPAT_DBOW2_DETAIL_CORE_H

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "binbow/compat/BowVector.h"
#include "binbow/compat/FeatureVector.h"
#include "binbow/compat/QueryResults.h"

namespace DBoW2 {
namespace binbow_detail {

// Descriptors as bytes: `count` rows of `code_size` bytes each.
struct DescriptorBytes {
  const unsigned char* data;
  std::size_t count;
  std::size_t code_size;
};

class VocabularyCore {
 public:
  VocabularyCore(int k, int L, WeightingType weighting, ScoringType scoring);
  VocabularyCore(const VocabularyCore& other);
  VocabularyCore& operator=(const VocabularyCore& other);
  ~VocabularyCore();

  // `images[i]` holds image i's descriptors; every row has `code_size` bytes.
  void create(const std::vector<std::vector<unsigned char> >& images, std::size_t code_size, int k,
              int L, WeightingType weighting, ScoringType scoring);

  bool empty() const;
  unsigned int size() const;
  std::size_t code_size() const;  // bytes per word; 0 when empty
  int branching() const;
  int levels() const;
  WeightingType weighting() const;
  ScoringType scoring() const;
  void set_weighting(WeightingType weighting);
  void set_scoring(ScoringType scoring);

  void transform(const DescriptorBytes& features, BowVector& v) const;
  void transform(const DescriptorBytes& features, BowVector& v, FeatureVector& fv,
                 int levelsup) const;
  WordId transform(const unsigned char* feature, std::size_t code_size) const;
  double score(const BowVector& a, const BowVector& b) const;

  NodeId parent_node(WordId wid, int levelsup) const;
  void words_from_node(NodeId nid, std::vector<WordId>& words) const;
  float effective_levels() const;
  const unsigned char* word_descriptor(WordId wid) const;
  WordValue word_weight(WordId wid) const;
  int stop_words(double min_weight);

  // Any format binbow reads (detected); throws std::runtime_error naming the file.
  void load(const std::string& filename);
  // Format chosen by the extension (DBoW2 YAML with FBrief's bit strings
  // when `bit_strings`); throws std::runtime_error naming the file.
  void save(const std::string& filename, bool bit_strings) const;
  // ORB-SLAM's text and binary formats; false on any failure.
  bool load_orbslam(const std::string& filename, bool binary);
  void save_orbslam(const std::string& filename, bool binary) const;

  struct Impl;

 private:
  friend class DatabaseCore;
  std::unique_ptr<Impl> impl_;
};

class DatabaseCore {
 public:
  DatabaseCore(bool use_di, int di_levels);
  DatabaseCore(const DatabaseCore& other);
  DatabaseCore& operator=(const DatabaseCore& other);
  ~DatabaseCore();

  // Drops every entry and indexes with `vocabulary` from now on.
  void set_vocabulary(const VocabularyCore& vocabulary, bool use_di, int di_levels);
  bool using_direct_index() const;
  int direct_index_levels() const;

  EntryId add(const BowVector& v, const FeatureVector& fv);
  void erase(EntryId id);
  void clear();
  unsigned int size() const;  // entries ever added since the last clear()

  void query(const BowVector& v, QueryResults& ret, int max_results, int max_id) const;
  const FeatureVector& features(EntryId id) const;

  // VINS's fork's query rule (TemplatedDatabase::setVinsQueryRule); until
  // set, the program's default (select_vins_query_rule()).
  void set_vins_query_rule(bool on);
  bool vins_query_rule() const;

  void save(const std::string& filename) const;
  // Replaces the database; `vocabulary` receives the one the file holds.
  void load(const std::string& filename, VocabularyCore& vocabulary);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Makes VINS's query rule the default of every database of the program that
// has not chosen (what the VINS spellings of the headers do, from a static
// initialiser, see names/ThirdParty/DBoW/); returns true.
bool select_vins_query_rule();

}  // namespace binbow_detail
}  // namespace DBoW2

#endif
