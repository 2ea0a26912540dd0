// --threads, for the commands that read and describe image sequences through
// a vision::FramePipeline: one help text and one bound everywhere.
#pragma once

#include <CLI/CLI.hpp>

#include "binbow/vision/frame_pipeline.h"

namespace binbow::cli {

inline void add_threads_option(CLI::App* command, unsigned& threads) {
  command
      ->add_option("--threads", threads,
                   "Threads reading and describing frames ahead, in order; the results are "
                   "the same for any number (0: every core)")
      ->check(CLI::Range(0u, vision::kMaxPipelineThreads))
      ->capture_default_str();
}

}  // namespace binbow::cli
