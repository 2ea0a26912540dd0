// DBoW2 compatibility layer: bag-of-words vectors as DBoW2 declares them.
//
// Part of binbow's DBoW2-compatible API (see DBoW2.h and docs/dbow2-compat.md).
// C++11, includes only the standard library: code written against DBoW2's
// BowVector.h compiles unchanged once the include path points here.
#ifndef BINBOW_COMPAT_DBOW2_BOW_VECTOR_H
#define BINBOW_COMPAT_DBOW2_BOW_VECTOR_H

#include <cstddef>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace DBoW2 {

/// Id of a word (a leaf of the vocabulary tree), numbered as DBoW2 does.
typedef unsigned int WordId;
/// Value of a word in a BoW vector.
typedef double WordValue;
/// Id of any node of the vocabulary tree; 0 is the root.
typedef unsigned int NodeId;

/// Norms for BowVector::normalize.
enum LNorm { L1, L2 };

/// How a word's occurrences in an image become its value (DBoW2's codes).
/// An int underneath, so that a code read from a file, such as 7, is a value
/// the setters can refuse rather than undefined behaviour.
enum WeightingType : int { TF_IDF, TF, IDF, BINARY };

/// How two BoW vectors are compared (DBoW2's codes). KL is a divergence
/// (lower is more similar); every other score is higher for more similar.
/// An int underneath, as WeightingType.
enum ScoringType : int { L1_NORM, L2_NORM, CHI_SQUARE, KL, BHATTACHARYYA, DOT_PRODUCT };

/// Sparse BoW vector: word id -> value, ordered by word id, as DBoW2's.
class BowVector : public std::map<WordId, WordValue> {
 public:
  BowVector() {}
  ~BowVector() {}

  /// Adds `v` to the value of word `id`, inserting the word if absent.
  void addWeight(WordId id, WordValue v);
  /// Inserts word `id` with value `v` only if the word is absent.
  void addIfNotExist(WordId id, WordValue v);
  /// Divides every value by the vector's L1 or L2 norm (nothing if it is 0).
  void normalize(LNorm norm_type);
  /// Prints "<id, value>, <id, value>, ..." as DBoW2 does.
  friend std::ostream& operator<<(std::ostream& out, const BowVector& v);
  /// Writes the dense vector of `W` words (values separated by spaces, 0 for
  /// absent words) to a text file that MATLAB can load, as DBoW2 does.
  /// Throws std::runtime_error naming the file if it cannot be written.
  void saveM(const std::string& filename, std::size_t W) const;
};

std::ostream& operator<<(std::ostream& out, const BowVector& v);

}  // namespace DBoW2

#endif
