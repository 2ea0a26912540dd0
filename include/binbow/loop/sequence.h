// Running the loop detector over an image sequence: the inputs read in
// order (vision::ImageSource), features extracted, every frame processed,
// with what a user of the results needs besides the LoopResult — the frame's
// file, the loop's other file and the inliers in pixels of the files. This
// is what `binbow detect-loops` and Python's `binbow.detect_loops` run.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "binbow/loop/loop_detector.h"
#include "binbow/vision/features.h"
#include "binbow/vision/frame_pipeline.h"
#include "binbow/vision/image_source.h"
#include "binbow/vocabulary.h"

namespace binbow::loop {

struct SequenceOptions {
  std::string descriptor = vision::kDefaultDescriptor;  // vision::extractor_names()
  int max_features = 0;                                 // 0: the extractor's default
  // An extractor configured otherwise (a BRIEF pattern, ...); when set,
  // `descriptor` and `max_features` are not used. Shared: extract() is const
  // and thread-safe.
  std::shared_ptr<const vision::FeatureExtractor> extractor;
  // Stride, max width, video rate, skip_unreadable, ...; frames above what
  // the extractor handles within its memory budget are refused unless
  // max_extracted_pixels is set (vision::limit_for_extractor).
  vision::ImageSourceOptions source;
  // A parameter file (JSON or YAML, LoopDetectorParams::load) whose keys
  // override the defaults; empty: the defaults alone. Ignored when the
  // SequenceDetector is given parameters.
  std::string params_file;
  // A JSON object of parameter keys applied after params_file's (the CLI's
  // parameter flags, --min-inliers ...); empty: none.
  std::string params_overrides;
  // Threads reading and describing frames ahead of the detector
  // (vision::FramePipeline), which takes them in order: every result is the
  // same for any number. 0: every hardware thread; 1: none besides the
  // caller's.
  unsigned threads = 0;
};

// Stage times of one frame in kStageNames order: features, transform,
// query, islands, verification, insertion.
inline constexpr std::size_t kStageCount = 6;
extern const char* const kStageNames[kStageCount];

// One frame of the sequence and what the detector made of it.
struct SequenceFrame {
  std::string file;  // vision::Frame::name: a path, or "video.mp4#N"
  // With ImageSourceOptions::skip_unreadable, why the frame could not be read
  // (vision::Frame::unreadable): it was processed without features, so it
  // matches nothing and keeps its index. Empty for a frame read.
  std::string unreadable;
  LoopResult result;
  double features_ms = 0;  // feature extraction
  // For a detection: the match's file, and the RANSAC inliers in pixels of
  // the two files (query x, y, match x, y; Frame::scale undone). Empty otherwise.
  std::string match_file;
  std::vector<std::array<float, 4>> inlier_points;

  // Milliseconds of each stage, kStageNames order.
  std::array<double, kStageCount> stage_ms() const;
};

// Frames per LoopStatus, indexed by its value.
using StatusCounts =
    std::array<std::size_t, static_cast<std::size_t>(LoopStatus::kNoGeometricConsistency) + 1>;

// Reads the inputs (images, folders, videos, lists: vision::ImageSource) and
// runs a LoopDetector over their frames, one next() call per frame. Frames
// are read and described ahead on options.threads threads
// (vision::FramePipeline); the detector takes them in order, so frames,
// errors and the detector's state are those of one thread.
//
// Parameters, unless given: for a video, LoopDetectorParams::for_frequency of
// the frames processed per second (ImageSource::frame_rate(): the video's
// rate, capped by video_fps, divided by the stride); for images, which have
// no rate, the paper's 1 Hz defaults; then the keys of options.params_file,
// then those of options.params_overrides.
class SequenceDetector {
 public:
  // Throws FileError for unreadable inputs or parameter files,
  // InvalidArgument for an unknown descriptor or a vocabulary whose word
  // length is not the extractor's code size.
  SequenceDetector(const std::vector<std::string>& inputs, Vocabulary vocabulary,
                   const SequenceOptions& options = {});
  SequenceDetector(const std::vector<std::string>& inputs, Vocabulary vocabulary,
                   const SequenceOptions& options, const LoopDetectorParams& params);
  // With no pre-trained vocabulary: LoopDetector::online for the extractor's
  // code size (vocabulary_options.descriptor, if empty, becomes its name).
  SequenceDetector(const std::vector<std::string>& inputs,
                   OnlineVocabularyOptions vocabulary_options, const SequenceOptions& options = {});
  SequenceDetector(const std::vector<std::string>& inputs,
                   OnlineVocabularyOptions vocabulary_options, const SequenceOptions& options,
                   const LoopDetectorParams& params);
  // Resumes a detector (LoopDetector::load of a saved state): its parameters,
  // and entry ids continuing after its images. Every frame is labelled with
  // its file (LoopDetector::set_label, a tab and the Frame::scale appended
  // when it is not 1), so that a loop with a frame of an earlier session,
  // resumed from a state saved by a SequenceDetector, names that frame's file
  // and gives its inliers in that file's pixels. Throws InvalidArgument when
  // the extractor's code size is not the detector's.
  SequenceDetector(const std::vector<std::string>& inputs, LoopDetector detector,
                   const SequenceOptions& options = {});
  SequenceDetector(SequenceDetector&&) noexcept;
  SequenceDetector& operator=(SequenceDetector&&) noexcept;
  ~SequenceDetector();

  // Processes the next frame into `frame`; false after the last one.
  bool next(SequenceFrame& frame);

  const LoopDetectorParams& params() const noexcept;
  // Why params().frequency is what it is, for a summary line:
  // "the saved state" (a resumed detector), "the parameters given" (to the
  // constructor), "--params" (the parameter
  // file set it), "video frames processed per second" or "the paper's
  // default; images have no frame rate".
  std::string frequency_origin() const;
  // Frames in the sequence when known before reading, else -1.
  long long size() const;
  std::size_t frames_processed() const noexcept;
  // Frames by status; unreadable frames are not counted here but in
  // skipped_frames().
  const StatusCounts& status_counts() const noexcept;
  // Frames that could not be read and were skipped (skip_unreadable).
  std::size_t skipped_frames() const noexcept;
  // Video frames the containers declared but could not be decoded.
  std::size_t unreadable_frames() const noexcept;
  const LoopDetector& detector() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Runs a whole sequence; `on_frame`, when given, is called after each frame
// (e.g. for progress) with the frames done and the total (0 when unknown).
std::vector<SequenceFrame> detect_sequence(
    SequenceDetector& sequence,
    const std::function<void(std::size_t done, std::size_t total)>& on_frame = {});

// Empty when some frame of a sequence of `frames` frames can have a loop
// candidate; otherwise why none can (candidates must be more than dislocal
// frames older than the query: a smaller dislocal is the remedy).
std::string no_candidate_reason(const LoopDetectorParams& params, std::size_t frames);

}  // namespace binbow::loop
