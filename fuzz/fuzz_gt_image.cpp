// libFuzzer target: the ground truth image reader (see fuzz_vision_targets.h).
#include "fuzz_vision_targets.h"
#include "vision/media_module.h"

// The image/video module is loaded before fuzzing starts, so that its own
// start-up allocations are not taken for leaks of the first input.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  binbow::vision::media_module();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return binbow::fuzz::run_target(binbow::fuzz::kVisionTargets, "gt_image", data, size);
}
