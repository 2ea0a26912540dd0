#include "binbow/loop/ground_truth.h"

#include <algorithm>
#include <cctype>
#include <string>

#include "binbow/error.h"
#include "core/regular_file.h"
#include "loop/evaluation/ground_truth_readers.h"

namespace binbow::loop {
namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

GroundTruth::GroundTruth(std::size_t frames,
                         const std::vector<std::pair<std::size_t, std::size_t>>& pairs) {
  if (frames > kMaxGroundTruthFrames) throw InvalidArgument("ground truth too large");
  binbow::detail::RunCollector runs(frames);
  for (const auto& [a, b] : pairs) {
    if (a >= frames || b >= frames)
      throw InvalidArgument("ground-truth pair (" + std::to_string(a) + ", " + std::to_string(b) +
                            ") outside " + std::to_string(frames) + " frames");
    runs.add(a, b);
  }
  *this = from_runs(frames, runs.take());
}

GroundTruth GroundTruth::from_runs(std::size_t frames,
                                   const std::vector<binbow::detail::LaterRun>& runs) {
  GroundTruth truth;
  truth.frames_ = frames;
  truth.ranges_.reserve(runs.size());
  for (const binbow::detail::LaterRun& run : runs) {
    if (truth.queries_.empty() || truth.queries_.back() != run.later) {
      truth.queries_.push_back(run.later);
      truth.range_begin_.push_back(truth.ranges_.size());
    }
    truth.ranges_.push_back({run.first, run.end});
    truth.pair_count_ += run.end - run.first;
  }
  truth.range_begin_.push_back(truth.ranges_.size());
  return truth;
}

GroundTruth GroundTruth::load(const std::string& path, const GroundTruthOptions& options) {
  const std::string name = lower(path);
  try {
    binbow::detail::require_regular_file(path);
    detail::LoadedGroundTruth loaded;
    bool image = false;
    for (const char* ext : {".bmp", ".png", ".pgm", ".pbm", ".tif", ".tiff", ".jpg", ".jpeg"})
      image = image || ends_with(name, ext);
    if (image) {
      loaded = detail::read_ground_truth_image(path, options);
    } else if (ends_with(name, ".mat")) {
      loaded = detail::read_ground_truth_mat(path, options);
    } else {
      loaded = detail::read_ground_truth_pairs(path, options);
    }
    return from_runs(loaded.frames, loaded.runs);
  } catch (const InvalidArgument& e) {
    throw FileError(path, e.what());
  }
}

bool GroundTruth::is_loop(std::size_t query, std::size_t match) const {
  const std::size_t later = std::max(query, match), earlier = std::min(query, match);
  if (later >= frames_ || later == earlier) return false;
  const Span<FrameRange> ranges = earlier_match_ranges(later);
  // The last range starting at or before `earlier` is the only one that can hold it.
  const auto after = std::upper_bound(
      ranges.begin(), ranges.end(), earlier,
      [](std::size_t frame, const FrameRange& range) { return frame < range.first; });
  return after != ranges.begin() && earlier < (after - 1)->end;
}

bool GroundTruth::has_loop(std::size_t query) const {
  return !earlier_match_ranges(query).empty();
}

std::vector<std::size_t> GroundTruth::loop_queries() const {
  return {queries_.begin(), queries_.end()};
}

Span<FrameRange> GroundTruth::earlier_match_ranges(std::size_t query) const {
  if (query >= frames_) return {};
  const auto it =
      std::lower_bound(queries_.begin(), queries_.end(), static_cast<std::uint32_t>(query));
  if (it == queries_.end() || *it != query) return {};
  const auto i = static_cast<std::size_t>(it - queries_.begin());
  return {ranges_.data() + range_begin_[i], range_begin_[i + 1] - range_begin_[i]};
}

std::vector<std::uint32_t> GroundTruth::earlier_matches(std::size_t query) const {
  std::vector<std::uint32_t> matches;
  for (const FrameRange& range : earlier_match_ranges(query))
    for (std::uint32_t j = range.first; j < range.end; ++j) matches.push_back(j);
  return matches;
}

}  // namespace binbow::loop
