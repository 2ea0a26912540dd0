// The image-input flags shared by every command that reads image sequences
// (--stride, --max-width, --video-fps, --max-pixels), so they read the same everywhere.
#pragma once

#include <CLI/CLI.hpp>

#include "binbow/vision/image_source.h"

namespace binbow::cli {

inline void add_image_source_options(CLI::App* command, vision::ImageSourceOptions& options) {
  command->add_option("--stride", options.stride, "Keep every N-th frame of the input sequence")
      ->check(CLI::Range(std::size_t{1}, vision::kMaxStride))
      ->capture_default_str();
  command
      ->add_option("--max-width", options.max_width,
                   "Downscale wider frames to this width, keeping the aspect (0: full size)")
      ->check(CLI::Range(0, vision::kMaxFrameWidth))
      ->capture_default_str();
  command
      ->add_option("--video-fps", options.video_fps,
                   "Videos: sample at most this many frames per second (0: every frame)")
      ->check(CLI::Range(0.0, vision::kMaxVideoFps))
      ->capture_default_str();
  command
      ->add_option("--max-pixels", options.max_pixels,
                   "Refuse images and video frames with more pixels, from their header, before "
                   "decoding")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 40))
      ->capture_default_str();
}

}  // namespace binbow::cli
