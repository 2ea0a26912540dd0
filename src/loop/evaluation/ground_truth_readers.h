// The ground-truth file readers behind GroundTruth::load, one per format
// (image, MATLAB .mat, text pairs), each in a file of its own so that it can
// be read, tested and fuzzed alone. Each returns the frame count the file
// declares (cut to the run's frames when known) and its same-place runs,
// throwing FileError naming the file and the problem.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "binbow/loop/ground_truth.h"
#include "loop/evaluation/ground_truth_runs.h"

namespace binbow::loop::detail {

using binbow::detail::LaterRun;
using binbow::detail::RunCollector;

// What a ground-truth file holds: its frame count and its runs, as
// RunCollector::take() gives them.
struct LoadedGroundTruth {
  std::size_t frames = 0;
  std::vector<LaterRun> runs;
};

// The frames of a ground truth declaring `declared` frames, cut to the run's
// `frames` when known.
inline std::size_t cut_to_run(std::size_t declared, const GroundTruthOptions& options) {
  return options.frames > 0 ? std::min(declared, options.frames) : declared;
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
