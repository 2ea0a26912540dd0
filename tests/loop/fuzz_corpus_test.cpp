// Replays the fuzz corpora of the vision and loop readers (parameters, BRIEF
// patterns, ground truth, loops.csv, the run record) through the normal
// build.
#include <gtest/gtest.h>

#include "../../fuzz/fuzz_vision_targets.h"
#include "support/fuzz_corpus.h"

namespace binbow {
namespace {

TEST(FuzzCorpus, VisionReadersLoadOrRejectEveryInputCleanly) {
  test::replay_fuzz_corpora(fuzz::kVisionTargets);
}

}  // namespace
}  // namespace binbow
