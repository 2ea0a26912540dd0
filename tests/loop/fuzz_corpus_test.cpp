// Replays the fuzz corpora of the vision readers (parameters, BRIEF
// patterns, ground truth, loops.csv) and of the run record through the
// normal build.
#include <gtest/gtest.h>

#include "../../fuzz/fuzz_cli_targets.h"
#include "../../fuzz/fuzz_vision_targets.h"
#include "support/fuzz_corpus.h"

namespace binbow {
namespace {

TEST(FuzzCorpus, VisionReadersLoadOrRejectEveryInputCleanly) {
  test::replay_fuzz_corpora(fuzz::kVisionTargets);
}

TEST(FuzzCorpus, RunRecordReaderLoadsOrRejectsEveryInputCleanly) {
  test::replay_fuzz_corpora(fuzz::kCliTargets);
}

}  // namespace
}  // namespace binbow
