#include "binbow/loop/decision_trail.h"

#include <algorithm>
#include <utility>

#include "binbow/loop/loop_detector.h"

namespace binbow::loop {

int TrailCheck::inliers_asked(const LoopDetectorParams& params) const {
  int asked = params.min_inliers;
  if (before_temporal_consistency) asked = std::max(asked, params.min_uncorroborated_inliers);
  if (rival_inliers > 0)
    asked = static_cast<int>(std::max(static_cast<std::size_t>(asked), rival_inliers + 1));
  return asked;
}

const TrailCheck* LoopDecisionTrail::accepted_check(EntryId entry) const {
  for (auto c = checks.rbegin(); c != checks.rend(); ++c)
    if (c->entry == entry && c->accepted()) return &*c;
  return nullptr;
}

TrailCheck* LoopDecisionTrail::accepted_check(EntryId entry) {
  return const_cast<TrailCheck*>(std::as_const(*this).accepted_check(entry));
}

}  // namespace binbow::loop
