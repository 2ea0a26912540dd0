// The record of one detect-loops run, saved beside loops.csv as
// "<loops.csv>.run.json": what was run (inputs, vocabulary, descriptor,
// parameters), every frame's outcome, the stage timings and the inliers of
// each loop. `evaluate` reads it to re-run detection (--sweep) and to draw
// the report.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "binbow/vision/image_source.h"
#include "binbow/vision/loop_detector.h"

namespace binbow::cli {

struct FrameRecord {
  std::string file;
  std::string status;    // to_string(LoopStatus)
  long long match = -1;  // candidate or loop, -1 if none
  double score = 0;
  double normalised_score = 0;
  std::size_t inliers = 0;
};

struct LoopRecord {
  std::size_t query = 0;
  std::size_t match = 0;
  std::vector<std::array<float, 4>> inliers;  // query x, y, match x, y
};

// Per-frame milliseconds of one stage.
struct StageTiming {
  std::string stage;
  std::vector<double> ms;
  double mean() const;
  double median() const;
  double max() const;
};

struct LoopRun {
  std::vector<std::string> inputs;  // absolute paths
  std::string vocabulary;           // absolute path
  std::string descriptor;
  int max_features = 0;               // 0: the extractor's default
  std::string params_json;            // LoopDetectorParams::to_json()
  vision::ImageSourceOptions source;  // how the inputs were read (stride, ...)
  std::vector<FrameRecord> frames;
  std::vector<LoopRecord> loops;    // inliers in pixels of the files (Frame::scale undone)
  std::vector<StageTiming> timing;  // features, transform, query, islands, verification, insertion

  static std::string path_for(const std::string& loops_csv) { return loops_csv + ".run.json"; }
  void save(const std::string& path) const;      // atomic
  static LoopRun load(const std::string& path);  // FileError on anything malformed
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
