// libFuzzer target: the detect-loops run record reader (see fuzz_cli_targets.h).
#include "fuzz_cli_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return binbow::fuzz::run_target(binbow::fuzz::kCliTargets, "loop_run", data, size);
}
