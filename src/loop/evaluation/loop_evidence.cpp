// The names of what accepted a loop, as run records and reports write them:
// apart from the detector, so that reading run records needs none of it.
#include "binbow/loop/corroboration.h"

namespace binbow::loop {

const char* to_string(LoopEvidence evidence) {
  switch (evidence) {
    case LoopEvidence::kNone:
      return "none";
    case LoopEvidence::kUnchecked:
      return "unchecked";
    case LoopEvidence::kStrongFit:
      return "strong-fit";
    case LoopEvidence::kStrongFitAlone:
      return "strong-fit-alone";
    case LoopEvidence::kNearPreviousLoop:
      return "near-previous-loop";
    case LoopEvidence::kRevisitPace:
      return "revisit-pace";
    case LoopEvidence::kNeighbour:
      return "neighbour";
  }
  return "?";
}

bool parse_loop_evidence(const std::string& name, LoopEvidence* evidence) {
  for (const LoopEvidence e :
       {LoopEvidence::kNone, LoopEvidence::kUnchecked, LoopEvidence::kStrongFit,
        LoopEvidence::kStrongFitAlone, LoopEvidence::kNearPreviousLoop, LoopEvidence::kRevisitPace,
        LoopEvidence::kNeighbour})
    if (name == to_string(e)) {
      *evidence = e;
      return true;
    }
  return false;
}

}  // namespace binbow::loop
