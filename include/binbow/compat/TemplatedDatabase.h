// DBoW2 compatibility layer: DBoW2's TemplatedDatabase over binbow::Database.
//
// C++11; includes the standard library and OpenCV core only (see DBoW2.h).
// Queries follow DBoW2's code: only entries with id < max_id are considered
// (all for max_id = -1; DBoW2's header comment says <=, its code <), the best
// max_results of them are returned (all for max_results <= 0), best first:
// highest score, lowest for KL; CHI_SQUARE and BHATTACHARYYA queries return
// only entries sharing at least 5 words with the query, as DBoW2's do.
// With setVinsQueryRule(true), L1_NORM queries also consider the newest
// entry, as VINS's fork of DBoW2 does.
// Entries with equal scores come in increasing id order (DBoW2's order among
// ties is unspecified). Scores come from binbow's inverted index, computed
// from single-precision BoW values: they agree with DBoW2's to about 1e-7.
#ifndef BINBOW_COMPAT_DBOW2_TEMPLATED_DATABASE_H
#define BINBOW_COMPAT_DBOW2_TEMPLATED_DATABASE_H

#include <cstddef>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "binbow/compat/BowVector.h"
#include "binbow/compat/FeatureVector.h"
#include "binbow/compat/QueryResults.h"
#include "binbow/compat/TemplatedVocabulary.h"
#include "binbow/compat/detail/core.h"

namespace DBoW2 {

/// An image database: inverted index for queries and, with `use_di`, a
/// direct index (each entry's FeatureVector at `di_levels` levels up, as
/// TemplatedVocabulary::transform computes it).
///
/// binbow extension: erase(id). Differences from DBoW2: save()/load() use
/// binbow's .bbdb format (DBoW2's YAML databases cannot be read).
///
/// Threads: query() may run from several threads at once (binbow's index
/// locks itself); retrieveFeatures() and every non-const method need
/// exclusive access, as everything in DBoW2 does.
template <class TDescriptor, class F>
class TemplatedDatabase {
 public:
  typedef TemplatedVocabulary<TDescriptor, F> Vocabulary;

  /// A database without vocabulary: call setVocabulary() before add().
  explicit TemplatedDatabase(bool use_di = true, int di_levels = 0)
      : voc_(NULL), core_(use_di, di_levels) {}
  /// A database over a copy of `voc` (any class derived from
  /// TemplatedVocabulary<TDescriptor, F>, as DBoW2 accepts).
  template <class T>
  explicit TemplatedDatabase(const T& voc, bool use_di = true, int di_levels = 0)
      : voc_(NULL), core_(use_di, di_levels) {
    setVocabulary(voc, use_di, di_levels);
  }
  TemplatedDatabase(const TemplatedDatabase& other)
      : voc_(other.voc_ ? new Vocabulary(*other.voc_) : NULL), core_(other.core_) {}
  /// Loads a database saved by save().
  TemplatedDatabase(const std::string& filename) : voc_(NULL), core_(true, 0) { load(filename); }
  TemplatedDatabase(const char* filename) : voc_(NULL), core_(true, 0) {
    load(std::string(filename));
  }
  virtual ~TemplatedDatabase() { delete voc_; }
  TemplatedDatabase& operator=(const TemplatedDatabase& other) {
    if (this != &other) {
      Vocabulary* voc = other.voc_ ? new Vocabulary(*other.voc_) : NULL;
      core_ = other.core_;
      delete voc_;
      voc_ = voc;
    }
    return *this;
  }

  /// Copies the vocabulary and clears the database.
  template <class T>
  void setVocabulary(const T& voc) {
    setVocabulary(voc, core_.using_direct_index(), core_.direct_index_levels());
  }
  template <class T>
  void setVocabulary(const T& voc, bool use_di, int di_levels = 0) {
    const Vocabulary& base = voc;
    Vocabulary* copy = new Vocabulary(base);
    try {
      core_.set_vocabulary(copy->core_, use_di, di_levels);
    } catch (...) {
      delete copy;
      throw;
    }
    delete voc_;
    voc_ = copy;
  }
  /// The database's own copy of the vocabulary (NULL without one).
  const Vocabulary* getVocabulary() const { return voc_; }

  /// Accepted for DBoW2 code that calls it; reserves nothing, since binbow's
  /// index grows by itself without copying its postings.
  void allocate(int nd = 0, int ni = 0) {
    (void)nd;
    (void)ni;
  }

  /// Transforms the features and adds the image; also returns its BoW vector
  /// and feature vector (at getDirectIndexLevels()) through the pointers
  /// given. Returns the new entry's id.
  EntryId add(const std::vector<TDescriptor>& features, BowVector* bowvec = NULL,
              FeatureVector* fvec = NULL) {
    return add_features(features, bowvec, fvec);
  }
  /// The same for descriptors of another type (see TemplatedVocabulary).
  template <class D>
  typename binbow_detail::if_descriptor<D, EntryId>::type add(const std::vector<D>& features,
                                                              BowVector* bowvec = NULL,
                                                              FeatureVector* fvec = NULL) {
    return add_features(features, bowvec, fvec);
  }
  /// Adds an image already transformed with this vocabulary; `fec` is kept
  /// only with a direct index. Throws std::out_of_range for word or node
  /// ids outside the vocabulary (and then adds nothing).
  EntryId add(const BowVector& vec, const FeatureVector& fec = FeatureVector()) {
    require_vocabulary();
    return core_.add(vec, fec);
  }

  /// binbow extension: removes entry `id`. It is never returned by a query
  /// again, its feature vector is gone, and its memory is freed; ids are not
  /// reused, so size() does not change. Throws std::runtime_error if the
  /// entry does not exist (never added, or already erased).
  void erase(EntryId id) { core_.erase(id); }

  /// Removes every entry; ids restart at 0.
  void clear() { core_.clear(); }
  /// Number of entries added since the last clear(), erased ones included:
  /// the id the next add() returns.
  unsigned int size() const { return core_.size(); }
  bool usingDirectIndex() const { return core_.using_direct_index(); }
  int getDirectIndexLevels() const { return core_.direct_index_levels(); }

  /// Queries with an image's features (transformed with the vocabulary).
  void query(const std::vector<TDescriptor>& features, QueryResults& ret, int max_results = 1,
             int max_id = -1) const {
    query_features(features, ret, max_results, max_id);
  }
  /// The same for descriptors of another type (see TemplatedVocabulary).
  template <class D>
  typename binbow_detail::if_descriptor<D>::type query(const std::vector<D>& features,
                                                       QueryResults& ret, int max_results = 1,
                                                       int max_id = -1) const {
    query_features(features, ret, max_results, max_id);
  }
  /// Queries with a BoW vector: see the top of this file for the rules.
  /// Throws std::out_of_range for word ids outside the vocabulary.
  void query(const BowVector& vec, QueryResults& ret, int max_results = 1, int max_id = -1) const {
    require_vocabulary();
    core_.query(vec, ret, max_results, max_id);
  }

  /// VINS's fork's query rule: VINS-Mono/Fusion's copy of DBoW2 also
  /// considers the newest entry (id size() - 1) in L1_NORM queries, whatever
  /// max_id (its queryL1 adds `entry_id == m_nentries - 1` to `entry_id <
  /// max_id`); VINS queries before adding each keyframe, so the newest entry
  /// is the previous keyframe. Off by default (DBoW2's rule); on by default in
  /// every database of a program that includes the VINS spellings of the
  /// headers (ThirdParty/DBoW/*.h, docs/dbow2-compat.md). Copies keep it.
  void setVinsQueryRule(bool on) { core_.set_vins_query_rule(on); }
  bool usingVinsQueryRule() const { return core_.vins_query_rule(); }

  /// The feature vector of entry `id`. The reference stays valid until the
  /// entry is erased or the database is cleared, loaded or assigned.
  /// Throws std::runtime_error without a direct index or for a missing entry.
  const FeatureVector& retrieveFeatures(EntryId id) const { return core_.features(id); }

  /// Writes the vocabulary and the entries to one binbow database file
  /// (.bbdb: inverted and direct index in single precision, with a CRC per
  /// section), atomically. Throws std::runtime_error naming the file.
  void save(const std::string& filename) const {
    require_vocabulary();
    core_.save(filename);
  }
  /// Reads a file written by save() (or by binbow's own tools with the
  /// vocabulary included). Every section's checksum is checked before it
  /// returns, so a damaged file fails here rather than at a later call.
  /// Throws std::runtime_error naming the file; the database is then unchanged.
  void load(const std::string& filename) {
    Vocabulary* voc = new Vocabulary();
    try {
      core_.load(filename, voc->core_);
    } catch (...) {
      delete voc;
      throw;
    }
    delete voc_;
    voc_ = voc;
  }

 private:
  template <class D>
  EntryId add_features(const std::vector<D>& features, BowVector* bowvec, FeatureVector* fvec) {
    BowVector aux_bow;
    BowVector& v = bowvec ? *bowvec : aux_bow;
    FeatureVector aux_fv;
    FeatureVector& fv = fvec ? *fvec : aux_fv;
    require_vocabulary();
    if (core_.using_direct_index() || fvec) {
      voc_->transform(features, v, fv, core_.direct_index_levels());
      return core_.using_direct_index() ? add(v, fv) : add(v);
    }
    voc_->transform(features, v);
    return add(v);
  }

  template <class D>
  void query_features(const std::vector<D>& features, QueryResults& ret, int max_results,
                      int max_id) const {
    BowVector vec;
    require_vocabulary();
    voc_->transform(features, vec);
    query(vec, ret, max_results, max_id);
  }

  void require_vocabulary() const {
    if (!voc_) throw std::logic_error("DBoW2::TemplatedDatabase: no vocabulary set");
  }

  Vocabulary* voc_;
  binbow_detail::DatabaseCore core_;
};

/// "Database: Entries = 10, Using direct index = yes, Direct index levels =
/// 4. Vocabulary: ...", as DBoW2 prints it.
template <class TDescriptor, class F>
std::ostream& operator<<(std::ostream& os, const TemplatedDatabase<TDescriptor, F>& db) {
  os << "Database: Entries = " << db.size()
     << ", Using direct index = " << (db.usingDirectIndex() ? "yes" : "no");
  if (db.usingDirectIndex()) os << ", Direct index levels = " << db.getDirectIndexLevels();
  os << ". ";
  if (db.getVocabulary()) os << *db.getVocabulary();
  return os;
}

}  // namespace DBoW2

#endif
