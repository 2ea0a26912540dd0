#include "binbow/loop/misses.h"

#include <unordered_map>

#include "binbow/loop/loop_detector.h"

namespace binbow::loop {

std::vector<MissedLoop> missed_loops(const std::vector<FrameRecord>& frames,
                                     const std::vector<Detection>& detections,
                                     const GroundTruth& truth) {
  // Per query with a detection: found (a true detection), or its first wrong
  // detection. Keyed by query, so memory follows the detections, not the frames.
  std::unordered_map<std::size_t, const Detection*> outcome;
  for (const Detection& d : detections) {
    check_detection_inside(d, truth);
    const Detection*& entry = outcome[d.query];
    if (entry == nullptr || truth.is_loop(d.query, d.match)) entry = &d;
  }
  const auto found = [&](std::size_t q) {
    const auto it = outcome.find(q);
    return it != outcome.end() && truth.is_loop(q, it->second->match);
  };
  std::vector<MissedLoop> misses;
  for (const std::size_t q : truth.loop_queries()) {
    if (found(q)) continue;
    MissedLoop miss;
    miss.query = q;
    if (q < frames.size()) {
      const FrameRecord& f = frames[q];
      miss.file = f.file;
      miss.status = f.status;
      miss.match = f.match;
      miss.correspondences = f.correspondences;
      miss.features = f.features;
      miss.inliers = static_cast<long long>(f.inliers);
      miss.normalised_score = f.normalised_score;
    } else if (const auto it = outcome.find(q); it != outcome.end()) {
      // No record: the wrong loop is all that is known.
      const Detection& d = *it->second;
      miss.file = d.query_file;
      miss.status = "loop-detected";
      miss.match = static_cast<long long>(d.match);
      miss.inliers = static_cast<long long>(d.inliers);
      miss.normalised_score = d.score;
    }
    if (miss.match >= 0 && static_cast<std::size_t>(miss.match) < truth.frames())
      miss.candidate_right = truth.is_loop(q, static_cast<std::size_t>(miss.match)) ? 1 : 0;
    misses.push_back(std::move(miss));
  }
  return misses;
}

bool geometrically_checked(const MissedLoop& miss) {
  return miss.status.empty() || miss.status == to_string(LoopStatus::kNoGeometricConsistency) ||
         miss.status == to_string(LoopStatus::kLoopDetected);
}

namespace {

// ", candidate 12 (right), 13 correspondences, 7 inliers" and the like.
std::string candidate_and_check(const MissedLoop& miss) {
  if (miss.match < 0) return miss.status.empty() ? ", candidate unknown" : ", no candidate";
  std::string line = ", candidate " + std::to_string(miss.match) +
                     (miss.candidate_right == 1   ? " (right)"
                      : miss.candidate_right == 0 ? " (wrong)"
                                                  : "");
  if (!geometrically_checked(miss)) return line + ", not checked geometrically";
  line += miss.correspondences < 0
              ? ", correspondences unknown"
              : ", " + std::to_string(miss.correspondences) + " correspondences";
  line += miss.inliers < 0 ? ", inliers unknown" : ", " + std::to_string(miss.inliers) + " inliers";
  return line;
}

}  // namespace

std::string format_missed_loop(const MissedLoop& miss) {
  std::string line = "  query " + std::to_string(miss.query) + ": " +
                     (miss.status.empty() ? "status unknown" : miss.status) +
                     candidate_and_check(miss);
  if (miss.features >= 0) line += ", " + std::to_string(miss.features) + " features";
  return line;
}

}  // namespace binbow::loop
