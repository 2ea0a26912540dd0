// The descriptor a loop detector state (.bbld) names, checked once for
// `detect-loops --resume-state` and `binbow info`, so that info never accepts
// a state that resuming refuses, and both say why in the same words.
#pragma once

#include <string>

#include "binbow/loop/loop_detector.h"

namespace binbow::cli {

// FileError naming `path` unless the state's descriptor name (when it has
// one) names an extractor binbow has, making descriptors of the state's size.
void check_saved_descriptor(const std::string& path, const loop::LoopDetectorFileInfo& saved);

}  // namespace binbow::cli
