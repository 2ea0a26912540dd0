// Evaluating loop detection against ground truth: the ground-truth formats
// users have (image matrices, MATLAB .mat matrices, text pairs), the
// detections file written by `binbow detect-loops`, and the paper's
// precision and recall.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "binbow/span.h"

namespace binbow::loop {

// The largest ground-truth image decoded by default, in pixels (10000 ×
// 10000): as vision::kDefaultMaxImagePixels. Larger sequences: .mat or pairs.
inline constexpr std::uint64_t kDefaultMaxGroundTruthImagePixels = 100'000'000;
// The largest frame count (and index + 1) a ground truth may have.
inline constexpr std::size_t kMaxGroundTruthFrames = 50'000'000;

struct GroundTruthOptions {
  // Index base of text pair files: 0 or 1; -1 detects it from a comment line
  // saying "0-based" or "1-based" (as in the shared data's pair files), else
  // from a 0 index appearing (0-based); a file with neither is an error
  // asking for the base.
  int pairs_index_base = -1;
  // The number of frames of the run being evaluated, when known (0: not
  // known). The ground truth is then cut to it: only the first `frames` rows
  // and columns of an image or .mat matrix are read, and pairs with an index
  // ≥ frames are ignored; text pairs then describe exactly `frames` frames.
  std::size_t frames = 0;
  // Ground-truth images declaring more pixels are refused from their header,
  // before decoding.
  std::uint64_t max_image_pixels = kDefaultMaxGroundTruthImagePixels;
};

// Which images of an N-image sequence show the same place. "Same place" is
// symmetric, so (i, j) and (j, i) are one fact; the diagonal is ignored. A
// query i has a loop when it shares a place with an earlier image j < i.
// Stored sparsely: memory and every operation depend on the number of pairs,
// never on N (a pair "49999999 0" costs what "1 0" does).
class GroundTruth {
 public:
  GroundTruth() = default;
  // From pairs of 0-based indices; frames = number of images (every index
  // must be < frames, and frames ≤ kMaxGroundTruthFrames: InvalidArgument).
  GroundTruth(std::size_t frames, const std::vector<std::pair<std::size_t, std::size_t>>& pairs);

  // By file type: .bmp/.png/.pgm/.tif/.tiff/.jpg square image (row = query,
  // column = match, non-zero = same place; not square: FileError), .mat
  // MATLAB level-5 file (the first two-dimensional numeric, logical or sparse
  // variable; non-zero = same place; read in bounded blocks, so large dense
  // matrices are fine), anything else text pairs "query match" per line ('#'
  // comments; space, tab or comma separated). Only regular files are read (a
  // FIFO is refused). Throws FileError naming the file and the problem.
  static GroundTruth load(const std::string& path, const GroundTruthOptions& options = {});

  std::size_t frames() const noexcept { return frames_; }
  bool is_loop(std::size_t query, std::size_t match) const;
  // Whether `query` shares a place with an earlier image.
  bool has_loop(std::size_t query) const;
  // Earlier images sharing a place with `query`, increasing.
  Span<std::uint32_t> earlier_matches(std::size_t query) const;
  std::size_t queries_with_loops() const noexcept { return queries_with_loops_; }
  // The queries that have a loop, increasing (queries_with_loops() of them).
  std::vector<std::size_t> loop_queries() const;
  std::size_t pair_count() const noexcept { return earlier_.size(); }

 private:
  // From (later, earlier) pairs, later > earlier and every index < frames (not
  // checked), duplicates allowed; sorted already is the fast path.
  static GroundTruth from_later_earlier(std::size_t frames,
                                        std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs);

  std::size_t frames_ = 0;
  std::size_t queries_with_loops_ = 0;
  // Pair i is (later_[i], earlier_[i]), sorted by later then earlier.
  std::vector<std::uint32_t> later_;
  std::vector<std::uint32_t> earlier_;
};

// One detected loop: a row of loops.csv.
struct Detection {
  std::size_t query = 0;  // 0-based index in input order
  std::size_t match = 0;
  std::string query_file;
  std::string match_file;
  double score = 0;
  std::size_t inliers = 0;
};

// loops.csv: header `query_index,match_index,query_file,match_file,score,inliers`
// and one row per detection (RFC 4180 quoting of file names; scores finite).
// Written atomically; reading throws FileError naming the file and line, and
// takes about 100 bytes per row plus the file names longer than 15
// characters (at most ~10 times the file's size; files up to 2 GiB).
void write_detections_csv(const std::string& path, const std::vector<Detection>& detections);
// The text write_detections_csv writes, header included.
std::string format_detections_csv(const std::vector<Detection>& detections);
std::vector<Detection> read_detections_csv(const std::string& path);

// The paper's measures: a detection at query i is a true positive when
// ground truth has (i, match); precision = true positives / detections (1
// when nothing is detected: no false alarm was raised); recall = queries with
// a true positive / queries that have any ground-truth loop.
struct PrecisionRecall {
  std::size_t detections = 0;
  std::size_t true_positives = 0;
  std::size_t false_positives = 0;
  std::size_t queries_with_loops = 0;
  std::size_t queries_found = 0;  // distinct queries with a true positive
  double precision = 1;
  double recall = 0;
};

// Throws InvalidArgument if a detection's index is outside the ground truth.
// O(detections × log) time, memory linear in the detections.
PrecisionRecall evaluate_detections(const std::vector<Detection>& detections,
                                    const GroundTruth& truth);

// A point of a precision–recall curve: the value of the swept parameter
// (α, a score threshold, ...) and the result at it.
struct PrCurvePoint {
  double parameter = 0;
  PrecisionRecall result;
};

// The highest recall among points with precision 1 and at least one
// detection; 0 if there is none.
double recall_at_full_precision(const std::vector<PrCurvePoint>& curve);

// The curve obtained by keeping only detections with score ≥ t, for t at
// every distinct score (increasing t): what can be read from a detections
// file alone, without re-running detection. One sort, then one pass:
// O(detections × log) time. InvalidArgument as evaluate_detections, or for a
// NaN score.
std::vector<PrCurvePoint> pr_curve_by_score(const std::vector<Detection>& detections,
                                            const GroundTruth& truth);

}  // namespace binbow::loop
