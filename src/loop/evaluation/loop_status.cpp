// The names of a frame's outcome, as run records and reports write them: apart
// from the detector, so that reading run records needs none of it.
#include "binbow/loop/loop_detector.h"

namespace binbow::loop {

const char* to_string(LoopStatus status) {
  switch (status) {
    case LoopStatus::kLoopDetected:
      return "loop-detected";
    case LoopStatus::kNoDatabaseResults:
      return "no-database-results";
    case LoopStatus::kLowNormalisationScore:
      return "low-normalisation-score";
    case LoopStatus::kLowScores:
      return "low-scores";
    case LoopStatus::kNoIslands:
      return "no-islands";
    case LoopStatus::kNoTemporalConsistency:
      return "no-temporal-consistency";
    case LoopStatus::kNoGeometricConsistency:
      return "no-geometric-consistency";
  }
  return "?";
}

}  // namespace binbow::loop
