// The record of one detect-loops run, saved beside loops.csv as
// "<loops.csv>.run.json": what was run (inputs, vocabulary, descriptor,
// parameters), every frame's outcome, the stage timings and the inliers of
// the loops the report draws. `evaluate` reads it to re-run detection
// (--sweep) and to draw the report.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "binbow/vision/image_source.h"
#include "binbow/loop/loop_detector.h"

namespace binbow::cli {

struct FrameRecord {
  std::string file;
  std::string status;    // to_string(LoopStatus)
  long long match = -1;  // candidate or loop, -1 if none
  double score = 0;
  double normalised_score = 0;
  std::size_t inliers = 0;
};

// The report draws the first kDrawnLoops loops, each with at most
// kDrawnInliers of its inliers (spread over all of them): more make the page
// too heavy to open and the lines unreadable. The run record keeps just
// those, so its size does not grow with the loops found (it reached 124 MB
// for 5,000 frames when it kept every inlier of every loop).
constexpr std::size_t kDrawnLoops = 300;
constexpr std::size_t kDrawnInliers = 200;
// A record grows ~230 bytes per frame plus at most ~3 MB of inliers: 1 GiB
// holds millions of frames, and no larger file is read.
constexpr std::uint64_t kMaxRunRecordBytes = std::uint64_t{1} << 30;

struct LoopRecord {
  std::size_t query = 0;
  std::size_t match = 0;
  std::vector<std::array<float, 4>> inliers;  // query x, y, match x, y; at most kDrawnInliers
};

// Per-frame milliseconds of one stage.
struct StageTiming {
  std::string stage;
  std::vector<double> ms;
  double mean() const;
  double median() const;
  double max() const;
};

// The stages timed for every frame, in pipeline order.
constexpr std::size_t kStageCount = 6;
extern const char* const kStageNames[kStageCount];  // features, transform, ... insertion

struct LoopRun {
  std::vector<std::string> inputs;  // absolute paths
  std::string vocabulary;           // absolute path
  std::string descriptor;
  int max_features = 0;               // 0: the extractor's default
  std::string params_json;            // LoopDetectorParams::to_json()
  vision::ImageSourceOptions source;  // how the inputs were read (stride, ...)
  std::vector<FrameRecord> frames;
  // The first kDrawnLoops loops found; inliers in pixels of the files (Frame::scale undone).
  std::vector<LoopRecord> loops;
  std::vector<StageTiming> timing;  // kStageNames, in that order

  static std::string path_for(const std::string& loops_csv) { return loops_csv + ".run.json"; }
  static LoopRun load(const std::string& path);  // FileError on anything malformed
};

// Writes a run record while the frames are processed, so that neither the
// record nor the memory it takes grows with more than the frames: each frame
// goes to the file at once; the loops the report draws and the stage timings
// (six numbers a frame, which the timing table needs all of) wait for
// finish(). Nothing is kept per frame beyond those timings.
class LoopRunWriter {
 public:
  // Writes the description of the run (`run`'s inputs, vocabulary,
  // descriptor, max_features, params_json and source) to `file`, which the
  // caller owns (a temporary staged for commit); errors name `target`.
  LoopRunWriter(std::FILE* file, const std::string& target, const LoopRun& run);
  LoopRunWriter(const LoopRunWriter&) = delete;
  LoopRunWriter& operator=(const LoopRunWriter&) = delete;

  void add_frame(const FrameRecord& frame, const std::array<double, kStageCount>& stage_ms);
  // Whether add_loop would keep the next loop, so its inliers are worth collecting.
  bool keeps_next_loop() const { return loops_.size() < kDrawnLoops; }
  // Keeps the loop, with kDrawnInliers of its inliers, while keeps_next_loop().
  void add_loop(std::size_t query, std::size_t match,
                const std::vector<std::array<float, 4>>& inliers);
  // Writes the kept loops and the timings, the end of the record. Throws
  // FileError naming the target when anything could not be written.
  void finish();

  std::size_t frames() const noexcept { return frames_; }
  const std::vector<LoopRecord>& loops() const noexcept { return loops_; }
  const std::vector<StageTiming>& timing() const noexcept { return timing_; }

 private:
  void write(const std::string& text);

  std::string target_;
  std::FILE* file_ = nullptr;
  std::size_t frames_ = 0;
  std::vector<LoopRecord> loops_;
  std::vector<StageTiming> timing_;
};

// The paper's Table III layout: one row per stage, mean / median / max ms per frame.
std::string format_timing_table(const std::vector<StageTiming>& timing);

// Writes `text` to `path` atomically (temporary file in the same directory, then rename).
void write_file_atomically(const std::string& path, const std::string& text);

}  // namespace binbow::cli

namespace binbow {
class Vocabulary;
}

namespace binbow::cli {

// --vocab, or the default vocabulary of the descriptor when empty; loads it and
// checks that its descriptor length is `code_size`. Returns the absolute path.
std::string load_loop_vocabulary(const std::string& vocab_argument, const std::string& descriptor,
                                 std::size_t code_size, Vocabulary& vocabulary);

}  // namespace binbow::cli
