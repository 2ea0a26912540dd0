// libFuzzer target: the online vocabulary's state reader (.bbov, see fuzz_targets.h).
#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return binbow::fuzz::run_target("bbov", data, size);
}
