// libFuzzer target: the detect-loops run record reader (see fuzz_vision_targets.h).
#include "fuzz_vision_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return binbow::fuzz::run_target(binbow::fuzz::kVisionTargets, "loop_run", data, size);
}
