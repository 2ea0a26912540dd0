// DBoW2 compatibility layer: the direct index of one image, as DBoW2 declares it.
//
// C++11, standard library only (see DBoW2.h).
#ifndef BINBOW_COMPAT_DBOW2_FEATURE_VECTOR_H
#define BINBOW_COMPAT_DBOW2_FEATURE_VECTOR_H

#include <iosfwd>
#include <map>
#include <vector>

#include "binbow/compat/BowVector.h"

namespace DBoW2 {

/// Vocabulary node -> indices of the image's features that pass through it
/// (at the level chosen by `levelsup` in TemplatedVocabulary::transform), in
/// increasing order. Two images' features under the same node are the
/// candidates for matching (ORB-SLAM's SearchByBoW, DLoopDetector).
class FeatureVector : public std::map<NodeId, std::vector<unsigned int> > {
 public:
  FeatureVector() {}
  ~FeatureVector() {}

  /// Appends feature `i_feature` to node `id`'s list.
  void addFeature(NodeId id, unsigned int i_feature);
  /// Prints "<node: [f, f, ...]>, <node: [...]>" as DBoW2 does.
  friend std::ostream& operator<<(std::ostream& out, const FeatureVector& v);
};

std::ostream& operator<<(std::ostream& out, const FeatureVector& v);

}  // namespace DBoW2

#endif
