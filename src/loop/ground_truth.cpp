#include "binbow/loop/ground_truth.h"

#include <algorithm>
#include <cctype>
#include <string>

#include "binbow/error.h"
#include "loop/ground_truth_readers.h"
#include "vision/regular_file.h"

namespace binbow::loop {
namespace {

using detail::add_pair;
using detail::LaterEarlier;

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
  LaterEarlier later_earlier;
  later_earlier.reserve(pairs.size());
  for (const auto& [a, b] : pairs) {
    if (a >= frames || b >= frames)
      throw InvalidArgument("ground-truth pair (" + std::to_string(a) + ", " + std::to_string(b) +
                            ") outside " + std::to_string(frames) + " frames");
    add_pair(a, b, frames, later_earlier);
  }
  *this = from_later_earlier(frames, std::move(later_earlier));
}

GroundTruth GroundTruth::from_later_earlier(std::size_t frames, LaterEarlier pairs) {
  if (!std::is_sorted(pairs.begin(), pairs.end())) std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  GroundTruth truth;
  truth.frames_ = frames;
  truth.later_.reserve(pairs.size());
  truth.earlier_.reserve(pairs.size());
  for (const auto& [later, earlier] : pairs) {
    if (truth.later_.empty() || truth.later_.back() != later) ++truth.queries_with_loops_;
    truth.later_.push_back(later);
    truth.earlier_.push_back(earlier);
  }
  return truth;
}

GroundTruth GroundTruth::load(const std::string& path, const GroundTruthOptions& options) {
  const std::string name = lower(path);
  try {
    vision::require_regular_file(path);
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
    return from_later_earlier(loaded.frames, std::move(loaded.pairs));
  } catch (const InvalidArgument& e) {
    throw FileError(path, e.what());
  }
}

bool GroundTruth::is_loop(std::size_t query, std::size_t match) const {
  const std::size_t later = std::max(query, match), earlier = std::min(query, match);
  if (later >= frames_ || later == earlier) return false;
  const Span<std::uint32_t> m = earlier_matches(later);
  return std::binary_search(m.begin(), m.end(), static_cast<std::uint32_t>(earlier));
}

bool GroundTruth::has_loop(std::size_t query) const {
  return !earlier_matches(query).empty();
}

std::vector<std::size_t> GroundTruth::loop_queries() const {
  std::vector<std::size_t> queries;
  queries.reserve(queries_with_loops_);
  for (const std::uint32_t later : later_)
    if (queries.empty() || queries.back() != later) queries.push_back(later);
  return queries;
}

Span<std::uint32_t> GroundTruth::earlier_matches(std::size_t query) const {
  if (query >= frames_) return {};
  const auto [first, last] =
      std::equal_range(later_.begin(), later_.end(), static_cast<std::uint32_t>(query));
  const auto offset = static_cast<std::size_t>(first - later_.begin());
  return {earlier_.data() + offset, static_cast<std::size_t>(last - first)};
}

}  // namespace binbow::loop
