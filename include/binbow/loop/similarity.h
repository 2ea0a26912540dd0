// The similarity matrix of a sequence — s(v_i, v_j) of every query i with
// every earlier image j, scored with the run's vocabulary — the figure
// loop-closure papers show with the ground truth and the detections over it.
// Long sequences are binned: a cell covers `bin` × `bin` frames and holds the
// highest score among them, so a loop stays visible however long the run.
#pragma once

#include <cstddef>
#include <vector>

#include "binbow/loop/loop_detector.h"
#include "binbow/vision/features.h"
#include "binbow/vocabulary.h"

namespace binbow::loop {

// At most this many cells per side (the matrix is at most 1000 × 1000 floats).
inline constexpr std::size_t kMaxSimilarityCells = 1000;
// At most this many query rows are scored against the earlier images: a
// longer sequence has one row per bin scored (every bin-th frame), so the
// work stays at most ~kMaxSimilarityQueries database queries. See docs/limits.md.
inline constexpr std::size_t kMaxSimilarityQueries = 5000;

struct SimilarityMatrix {
  std::size_t frames = 0;  // images of the sequence; 0: no matrix
  std::size_t bin = 1;     // frames per cell side
  std::size_t cells = 0;   // cells per side: ceil(frames / bin)
  // Every query row was scored (false: every bin-th one, see kMaxSimilarityQueries).
  bool every_query = true;
  // Row-major cells × cells; cell (r, c) is the highest s(v_i, v_j) with i in
  // bin r, j in bin c and j < i (0 where no pair shares a word; the upper
  // triangle stays 0).
  std::vector<float> scores;

  bool empty() const noexcept { return frames == 0; }
  float at(std::size_t row, std::size_t column) const { return scores[row * cells + column]; }
  // The cell of a frame.
  std::size_t cell(std::size_t frame) const { return frame / bin; }
};

// The matrix of images described by `descriptors` (frame i = descriptors[i]),
// scored with `vocabulary` as the loop detector scores them.
// Throws InvalidArgument if a descriptor size differs from the vocabulary's.
SimilarityMatrix similarity_matrix(const Vocabulary& vocabulary,
                                   const std::vector<DescriptorView>& descriptors);
SimilarityMatrix similarity_matrix(const Vocabulary& vocabulary,
                                   const std::vector<vision::Features>& features);
// The matrix of the images a LoopDetector has processed, from the features
// it keeps for the geometric check; a forgotten image (LoopDetector::forget)
// scores as one without features. Throws InvalidArgument when it keeps none
// (GeometricCheck::kNone).
SimilarityMatrix similarity_matrix(const LoopDetector& detector);
// For a run without a pre-trained vocabulary: an online vocabulary (default
// options, descriptors of `code_size` bytes) grown over all the images, then
// the matrix scored with its words, as similarity_matrix(detector) does for
// LoopDetector::online.
SimilarityMatrix online_similarity_matrix(std::size_t code_size,
                                          const std::vector<vision::Features>& features,
                                          const OnlineVocabularyOptions& options = {});

}  // namespace binbow::loop
