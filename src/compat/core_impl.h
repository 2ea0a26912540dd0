// The state behind DBoW2::binbow_detail::VocabularyCore, shared with the
// database core.
#pragma once

#include <string>
#include <vector>

#include "binbow/compat/detail/core.h"
#include "binbow/vocabulary.h"

namespace DBoW2 {
namespace binbow_detail {

struct VocabularyCore::Impl {
  int k = 10;
  int L = 5;
  // Kept apart from the binbow vocabulary's own types: DBoW2 lets users
  // change them at any time, and they only matter to transform(), score()
  // and what save() and a database record (see current()).
  WeightingType weighting = TF_IDF;
  ScoringType scoring = L1_NORM;
  binbow::Vocabulary vocabulary;
  std::vector<binbow::NodeId> parent;     // per node
  std::vector<binbow::NodeId> word_node;  // per word

  // Takes a vocabulary and its parameters.
  void assign(binbow::Vocabulary v);
  // The vocabulary with this object's weighting and scoring types.
  binbow::Vocabulary current() const;
};

// binbow's errors, rethrown as the standard exception the DBoW2 layer
// documents, with `filename` in the message.
[[noreturn]] void rethrow_naming(const std::string& filename);

}  // namespace binbow_detail
}  // namespace DBoW2
