// A detector templated over the descriptor and its functions, written as
// DLoopDetector's TemplatedLoopDetector.h is: DBoW2's headers by their bare
// DLib-style names, a TemplatedDatabase with a direct index that the
// detector fills with the vectors the database's own vocabulary computes.
#ifndef BINBOW_PACKAGE_DBOW2_NAMES_TEMPLATED_PLACE_DETECTOR_H
#define BINBOW_PACKAGE_DBOW2_NAMES_TEMPLATED_PLACE_DETECTOR_H

#include <vector>

#include "BowVector.h"
#include "QueryResults.h"
#include "TemplatedDatabase.h"
#include "TemplatedVocabulary.h"

template <class TDescriptor, class F>
class TemplatedPlaceDetector {
 public:
  TemplatedPlaceDetector(const DBoW2::TemplatedVocabulary<TDescriptor, F>& voc, int di_levels)
      : m_database(new DBoW2::TemplatedDatabase<TDescriptor, F>(voc, true, di_levels)),
        m_di_levels(di_levels) {}
  ~TemplatedPlaceDetector() { delete m_database; }

  /// Adds an image: its BoW and feature vectors, as DLoopDetector's
  /// detectLoop computes them, through the database's vocabulary.
  DBoW2::EntryId add(const std::vector<TDescriptor>& features) {
    DBoW2::BowVector bowvec;
    DBoW2::FeatureVector featvec;
    m_database->getVocabulary()->transform(features, bowvec, featvec, m_di_levels);
    return m_database->add(bowvec, featvec);
  }

  void query(const std::vector<TDescriptor>& features, DBoW2::QueryResults& ret, int max_results,
             int max_id) const {
    DBoW2::BowVector bowvec;
    m_database->getVocabulary()->transform(features, bowvec);
    m_database->query(bowvec, ret, max_results, max_id);
  }

  const DBoW2::FeatureVector& directIndex(DBoW2::EntryId id) const {
    return m_database->retrieveFeatures(id);
  }
  const DBoW2::TemplatedDatabase<TDescriptor, F>* getDatabase() const { return m_database; }

 private:
  TemplatedPlaceDetector(const TemplatedPlaceDetector&);
  TemplatedPlaceDetector& operator=(const TemplatedPlaceDetector&);

  DBoW2::TemplatedDatabase<TDescriptor, F>* m_database;
  int m_di_levels;
};

#endif
