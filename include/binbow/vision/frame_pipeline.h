// Frames of an ImageSource with their features, read, decoded and described
// ahead of their use on worker threads, and delivered strictly in sequence
// order: what `binbow detect-loops`, `db` and `bench` and Python's
// `detect_loops` run to keep every core busy while the caller (a loop
// detector, a database) consumes the frames one by one.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"

namespace binbow::vision {

// A frame of the sequence and its features.
struct ExtractedFrame {
  // The frame as ImageSource delivered it (name, index, scale, unreadable),
  // except its image, released once described: frames waiting in the queue
  // hold only their features.
  Frame frame;
  // Empty (of the extractor's code size) for a frame skipped as unreadable
  // (frame.unreadable set, ImageSourceOptions::skip_unreadable).
  Features features;
  double features_ms = 0;  // what extract_features took, on the thread that ran it
};

// The most threads a pipeline runs: more only adds memory and contention.
inline constexpr unsigned kMaxPipelineThreads = 256;

struct FramePipelineOptions {
  // Threads reading and describing frames. 0: every hardware thread.
  // 1: no thread is started; next() reads and describes each frame itself,
  // exactly as a loop over ImageSource::next and extract_features would.
  // At most kMaxPipelineThreads (InvalidArgument beyond).
  unsigned threads = 0;
  // The most frames taken from the source and not yet returned by next():
  // the pipeline's memory is this many frames' decoded images and features,
  // whatever the length of the sequence. 0: twice the threads.
  std::size_t queue_frames = 0;
};

// Reads `source` and describes its frames with `extractor`, `threads` frames
// at a time. The frames are taken from the source one at a time, in order
// (the source decodes them, one worker at a time) and described in parallel;
// next() returns them in the source's order, so that what a caller does with
// them, and every error, is the same for any number of threads:
// - an error reading a frame (ImageSource::next's FileError) or describing it
//   (extract_features') is thrown by the next() call that would have returned
//   that frame, after every earlier frame was returned; the next call
//   continues with the frame after it, as ImageSource does;
// - workers start at the first next() and are stopped and joined by the
//   destructor, also while frames are still queued or after an error: a
//   worker finishes the frame it is reading or describing first.
// Calls are not thread-safe: one consumer calls next().
class FramePipeline {
 public:
  // Throws InvalidArgument for a null extractor or threads beyond
  // kMaxPipelineThreads.
  FramePipeline(ImageSource source, std::shared_ptr<const FeatureExtractor> extractor,
                FramePipelineOptions options = {});
  FramePipeline(FramePipeline&&) noexcept;
  FramePipeline& operator=(FramePipeline&&) noexcept;
  ~FramePipeline();

  // The next frame and its features, or false after the last one.
  bool next(ExtractedFrame& frame);

  // ImageSource::size(), frame_rate() and unreadable_frames() of the
  // source; unreadable_frames() counts what the workers have read, which
  // may be ahead of what next() returned, and is final once next() returned
  // false.
  long long size() const;
  double frame_rate() const;
  std::size_t unreadable_frames() const noexcept;

  unsigned threads() const noexcept;          // resolved: never 0
  std::size_t queue_frames() const noexcept;  // resolved: never 0
  // The most frames that were ever taken from the source and not yet
  // returned by next() at once: at most queue_frames().
  std::size_t peak_frames_in_flight() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace binbow::vision
