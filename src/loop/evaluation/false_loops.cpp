#include "binbow/loop/false_loops.h"

#include <string>
#include <utility>

namespace binbow::loop {

std::vector<FalseLoop> false_loops(const std::vector<FrameRecord>& frames,
                                   const std::vector<Detection>& detections,
                                   const GroundTruth& truth) {
  std::vector<FalseLoop> wrong;
  for (const Detection& d : detections) {
    check_detection_inside(d, truth);
    if (truth.is_loop(d.query, d.match)) continue;
    FalseLoop loop{d.query, d.match, d.query_file, d.inliers, d.score, "", -1};
    // The record's frame is this detection's only if it names the same match.
    if (d.query < frames.size() && frames[d.query].match == static_cast<long long>(d.match)) {
      const FrameRecord& f = frames[d.query];
      if (loop.file.empty()) loop.file = f.file;
      loop.accepted_by = f.accepted_by;
      loop.localised_from = f.localised_from;
    }
    wrong.push_back(std::move(loop));
  }
  return wrong;
}

std::string format_false_loop(const FalseLoop& loop) {
  std::string line =
      "  query " + std::to_string(loop.query) + ": match " + std::to_string(loop.match) + ", " +
      std::to_string(loop.inliers) + " inliers, " +
      (loop.accepted_by.empty() ? "evidence unknown" : "accepted by " + loop.accepted_by);
  if (loop.localised_from >= 0) line += ", localised from " + std::to_string(loop.localised_from);
  return line;
}

}  // namespace binbow::loop
