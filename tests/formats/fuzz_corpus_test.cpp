// Replays the fuzz corpora of the core readers (vocabularies, databases,
// gzip and tar) through the normal build.
#include <gtest/gtest.h>

#include "../../fuzz/fuzz_targets.h"
#include "support/fuzz_corpus.h"

namespace binbow {
namespace {

TEST(FuzzCorpus, EveryInputLoadsOrIsRejectedCleanly) {
  test::replay_fuzz_corpora(fuzz::kTargets);
}

}  // namespace
}  // namespace binbow
