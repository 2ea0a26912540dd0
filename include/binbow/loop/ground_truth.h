// Ground truth for loop detection: which images of a sequence show the same
// place, read from the formats users have (image matrices, MATLAB .mat
// matrices, text pairs).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "binbow/span.h"

namespace binbow::detail {
struct LaterRun;
}

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

// Consecutive frames [first, end).
struct FrameRange {
  std::uint32_t first = 0;
  std::uint32_t end = 0;
  std::uint32_t size() const noexcept { return end - first; }
  friend bool operator==(const FrameRange& a, const FrameRange& b) {
    return a.first == b.first && a.end == b.end;
  }
};

// Which images of an N-image sequence show the same place. "Same place" is
// symmetric, so (i, j) and (j, i) are one fact; the diagonal is ignored. A
// query i has a loop when it shares a place with an earlier image j < i.
// Stored as ranges of consecutive earlier images per query: memory and every
// operation depend on the number of ranges, never on N nor on the pairs they
// hold (a pair "49999999 0" costs what "1 0" does, and an all-ones 10,000²
// matrix takes 10,000 ranges, not 50 million pairs).
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
  // Earlier images sharing a place with `query`, as increasing, disjoint,
  // non-adjacent ranges (empty if none).
  Span<FrameRange> earlier_match_ranges(std::size_t query) const;
  // The same images one by one, increasing: as many as the ranges hold.
  std::vector<std::uint32_t> earlier_matches(std::size_t query) const;
  std::size_t queries_with_loops() const noexcept { return queries_.size(); }
  // The queries that have a loop, increasing (queries_with_loops() of them).
  std::vector<std::size_t> loop_queries() const;
  // The number of (later, earlier) same-place pairs.
  std::size_t pair_count() const noexcept { return pair_count_; }
  // The number of ranges stored (what memory follows).
  std::size_t range_count() const noexcept { return ranges_.size(); }

 private:
  // From runs sorted by (later, first), merged (disjoint, non-adjacent).
  static GroundTruth from_runs(std::size_t frames,
                               const std::vector<binbow::detail::LaterRun>& runs);

  std::size_t frames_ = 0;
  std::size_t pair_count_ = 0;
  // Query queries_[i] has the ranges ranges_[range_begin_[i] .. range_begin_[i + 1]).
  std::vector<std::uint32_t> queries_;
  std::vector<std::size_t> range_begin_;
  std::vector<FrameRange> ranges_;
};

}  // namespace binbow::loop
