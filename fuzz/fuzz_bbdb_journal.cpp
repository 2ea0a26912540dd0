// libFuzzer target: the database journal reader (see fuzz_targets.h).
#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return binbow::fuzz::run_target("bbdb_journal", data, size);
}
