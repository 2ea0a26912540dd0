// The ground-truth file readers behind GroundTruth::load, one per format
// (image, MATLAB .mat, text pairs), each in a file of its own so that it can
// be read, tested and fuzzed alone. Each returns the frame count the file
// declares (cut to the run's frames when known) and its (later, earlier)
// pairs, throwing FileError naming the file and the problem.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "binbow/loop/ground_truth.h"

namespace binbow::loop::detail {

// (later, earlier) index pairs, as GroundTruth::from_later_earlier takes them.
using LaterEarlier = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

// What a ground-truth file holds: its frame count and its pairs.
struct LoadedGroundTruth {
  std::size_t frames = 0;
  LaterEarlier pairs;
};

// The frames of a ground truth declaring `declared` frames, cut to the run's
// `frames` when known.
inline std::size_t cut_to_run(std::size_t declared, const GroundTruthOptions& options) {
  return options.frames > 0 ? std::min(declared, options.frames) : declared;
}

// Adds the pair (a, b) unless it is on the diagonal or outside `frames`.
inline void add_pair(std::size_t a, std::size_t b, std::size_t frames, LaterEarlier& pairs) {
  if (a == b || a >= frames || b >= frames) return;
  pairs.emplace_back(static_cast<std::uint32_t>(std::max(a, b)),
                     static_cast<std::uint32_t>(std::min(a, b)));
}

// A square greyscale image: row = query, column = match, non-zero = same place.
LoadedGroundTruth read_ground_truth_image(const std::string& path,
                                          const GroundTruthOptions& options);
// The first two-dimensional numeric, logical or sparse variable of a MATLAB
// level-5 or -v7.3 file; non-zero = same place.
LoadedGroundTruth read_ground_truth_mat(const std::string& path, const GroundTruthOptions& options);
// Text pairs "query match" per line, 0- or 1-based.
LoadedGroundTruth read_ground_truth_pairs(const std::string& path,
                                          const GroundTruthOptions& options);

}  // namespace binbow::loop::detail
