// A whole sequence through a loop detector with the bundled vocabulary of a
// descriptor, keeping every frame's result and decision trail, for tests
// that look at why a loop was (or was not) reported.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "binbow/loop/decision_trail.h"
#include "binbow/loop/ground_truth.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "support/test_support.h"

namespace binbow::test {

struct TrailedRun {
  std::vector<loop::LoopResult> results;
  std::vector<loop::LoopDecisionTrail> trails;  // one per frame
};

// The images of `folder`, in natural order, with data/vocab/<descriptor>_default.bbw.
inline TrailedRun run_with_trails(const std::string& folder, const std::string& descriptor,
                                  const loop::LoopDetectorParams& params) {
  loop::LoopDetector detector(
      Vocabulary::load(source_path("data/vocab/" + descriptor + "_default.bbw")), params);
  const auto extractor = vision::make_extractor(descriptor);
  vision::ImageSource source({folder});
  vision::Frame frame;
  TrailedRun run;
  while (source.next(frame)) {
    run.trails.emplace_back();
    run.results.push_back(detector.process(extractor->extract(frame.image), run.trails.back()));
  }
  return run;
}

// The (query, match) of every detection that `truth` does not hold.
inline std::vector<std::pair<EntryId, EntryId>> false_loops(const TrailedRun& run,
                                                            const loop::GroundTruth& truth) {
  std::vector<std::pair<EntryId, EntryId>> out;
  for (const loop::LoopResult& r : run.results)
    if (r.detection() && !truth.is_loop(r.query, r.match)) out.emplace_back(r.query, r.match);
  return out;
}

}  // namespace binbow::test
