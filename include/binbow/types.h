// Identifiers and the weighting and scoring types of DBoW2, with the same
// numeric values as DBoW2's WeightingType and ScoringType enums (they are
// stored in vocabulary files).
#pragma once

#include <cstdint>
#include <string>

namespace binbow {

using WordId = std::uint32_t;   // index of a leaf of the vocabulary tree
using NodeId = std::uint32_t;   // index of any node of the tree; 0 is the root
using EntryId = std::uint32_t;  // index of an image in a Database

// How a word's occurrences in an image become the word's value in a BoW vector.
enum class Weighting : std::uint8_t {
  kTfIdf = 0,   // term frequency × log(N / N_i)
  kTf = 1,      // term frequency
  kIdf = 2,     // log(N / N_i), once per word present
  kBinary = 3,  // 1 per word present
};

// How two BoW vectors are compared; every score is "higher is more similar".
enum class Scoring : std::uint8_t {
  kL1 = 0,             // 1 − ½‖v − w‖₁ on L1-normalised vectors, in [0, 1]
  kL2 = 1,             // 1 − √(1 − v·w) on L2-normalised vectors, in [0, 1]
  kChiSquare = 2,      // 2 Σ v_i w_i / (v_i + w_i) on L1-normalised vectors, in [0, 1]
  kKL = 3,             // Kullback–Leibler divergence Σ v_i log(v_i / w_i) (not symmetric)
  kBhattacharyya = 4,  // Σ √(v_i w_i) on L1-normalised vectors, in [0, 1]
  kDotProduct = 5,     // Σ v_i w_i, no normalisation
};

// Lower-case names used in files and on the command line:
// "tf-idf", "tf", "idf", "binary"; "l1", "l2", "chi-square", "kl",
// "bhattacharyya", "dot-product".
const char* to_string(Weighting weighting);
const char* to_string(Scoring scoring);
// Parse a name (case-insensitive, '_' accepted for '-'); throws InvalidArgument
// listing the accepted names.
Weighting parse_weighting(const std::string& name);
Scoring parse_scoring(const std::string& name);
// From DBoW2's numeric codes; throws InvalidArgument if out of range.
Weighting weighting_from_code(int code);
Scoring scoring_from_code(int code);

}  // namespace binbow
