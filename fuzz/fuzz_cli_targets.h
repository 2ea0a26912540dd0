// The fuzz target of the CLI's own reader of untrusted files: the run record
// detect-loops writes beside loops.csv (apps/binbow/loop_run.cpp, compiled
// into the target and the corpus test until the record moves into the
// library). Same contract as fuzz_targets.h.
#pragma once

#include <cstddef>
#include <cstdint>

#include "fuzz_vision_targets.h"
#include "loop_run.h"

namespace binbow::fuzz {

// evaluate --sweep re-runs detection with the recorded parameters.
inline void load_loop_run(const std::uint8_t* data, std::size_t size) {
  const cli::LoopRun run = cli::LoopRun::load(input_file(data, size, ".run.json"));
  (void)loop::LoopDetectorParams::from_json(run.params_json, "the run record's params");
}

inline const Target kCliTargets[] = {
    {"loop_run", load_loop_run},
};

}  // namespace binbow::fuzz
