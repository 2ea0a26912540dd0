// The stages of a frame and their times, as run records and the timing table
// name them: apart from the sequence runner, so that reading run records
// needs none of it.
#include "binbow/loop/sequence.h"

namespace binbow::loop {

const char* const kStageNames[kStageCount] = {"features", "transform",    "query",
                                              "islands",  "verification", "insertion"};

std::array<double, kStageCount> SequenceFrame::stage_ms() const {
  const LoopStageTimes& t = result.times;
  return {features_ms, t.transform_ms, t.query_ms, t.islands_ms, t.verification_ms, t.insertion_ms};
}

}  // namespace binbow::loop
