// libFuzzer target: the loop detector's state reader (.bbld, see fuzz_vision_targets.h).
#include "fuzz_vision_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return binbow::fuzz::run_target(binbow::fuzz::kVisionTargets, "bbld", data, size);
}
