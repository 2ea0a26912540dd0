// The image-input flags shared by every command that reads image sequences
// (--stride, --max-width, --video-fps, --max-pixels, --skip-unreadable), so
// they read the same everywhere.
#pragma once

#include <cstdio>
#include <string>

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
  // Given, it is the limit for feature extraction too: the user accepts the
  // memory; otherwise each extractor's own limit (vision::limit_for_extractor)
  // also applies.
  command
      ->add_option("--max-pixels", options.max_pixels,
                   "Refuse images and video frames with more pixels, from their header, before "
                   "decoding; by default also those above what the extractor handles in 2 GiB "
                   "of memory (AKAZE: 17.8 million pixels, docs/limits.md)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 40))
      ->each([&options](const std::string& value) {
        options.max_extracted_pixels = std::stoull(value);
        options.extraction_limit_reason = "the limit given by --max-pixels";
      })
      ->capture_default_str();
}

// --skip-unreadable, for the commands that read long sequences.
inline void add_skip_unreadable_option(CLI::App* command, vision::ImageSourceOptions& options) {
  command->add_flag("--skip-unreadable", options.skip_unreadable,
                    "Warn about an image (or video frame) that cannot be read and go on without "
                    "it, instead of stopping; it keeps its frame number");
}

// Warns on stderr about a frame skipped with --skip-unreadable; true when
// `frame` is such a frame.
inline bool warn_if_unreadable(const std::string& file, const std::string& problem) {
  if (problem.empty()) return false;
  std::fprintf(stderr, "binbow: warning: %s: %s; skipped (--skip-unreadable)\n", file.c_str(),
               problem.c_str());
  return true;
}

}  // namespace binbow::cli
