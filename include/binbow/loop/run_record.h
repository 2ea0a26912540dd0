// The files a loop-detection run leaves, as `binbow detect-loops` writes
// them: loops.csv (the detections, see evaluation.h) and beside it the run
// record "<loops.csv>.run.json": what was run (inputs, vocabulary,
// descriptor, parameters, image-source options), every frame's outcome, the
// stage timings and the inliers of the loops the report draws. `binbow
// evaluate` reads the record to re-run detection (sweeps) and to draw the
// report. Format: docs/loop-detection.md.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/provenance.h"
#include "binbow/loop/sequence.h"
#include "binbow/vision/image_source.h"

namespace binbow::loop {

// The run record's status of a frame that could not be read and was skipped
// (ImageSourceOptions::skip_unreadable): it keeps its index, has no
// features and matches nothing.
inline constexpr const char* kUnreadableFrameStatus = "unreadable";

struct FrameRecord {
  std::string file;
  std::string status;    // to_string(LoopStatus), or kUnreadableFrameStatus
  long long match = -1;  // candidate or loop, -1 if none
  double score = 0;
  double normalised_score = 0;
  std::size_t inliers = 0;
  // Putative correspondences given to RANSAC (LoopResult::correspondences);
  // -1 when not known (records written before the key existed).
  long long correspondences = -1;
  long long features = -1;  // keypoints of the frame (LoopResult::features); -1 not known
  // Of a loop: what accepted it (to_string(LoopResult::accepted_by)), and the
  // island entry localisation moved it from (LoopResult::localised_from; -1
  // when it was not moved). Empty / -1 for other frames and in records
  // written before the keys existed.
  std::string accepted_by;
  long long localised_from = -1;
};

// What the run record keeps of a frame.
FrameRecord frame_record(const SequenceFrame& frame);

// The report draws the first kDrawnLoops loops, each with at most
// kDrawnInliers of its inliers (spread over all of them): more make the page
// too heavy to open and the lines unreadable. The run record keeps just
// those, so its size does not grow with the loops found (it reached 124 MB
// for 5,000 frames when it kept every inlier of every loop).
inline constexpr std::size_t kDrawnLoops = 300;
inline constexpr std::size_t kDrawnInliers = 200;
// A record grows ~230 bytes per frame plus at most ~3 MB of inliers: 1 GiB
// holds millions of frames, and no larger file is read.
inline constexpr std::uint64_t kMaxRunRecordBytes = std::uint64_t{1} << 30;

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

// The stage timings of `frames`, kStageNames order.
std::vector<StageTiming> stage_timings(const std::vector<SequenceFrame>& frames);

// The paper's Table III layout: one row per stage, mean / median / max ms per
// frame, and their total.
std::string format_timing_table(const std::vector<StageTiming>& timing);

struct LoopRun {
  // Which binbow ran, when and with what command ("provenance" in the
  // record; empty in records written before the key existed).
  Provenance provenance;
  std::vector<std::string> inputs;  // absolute paths
  std::string vocabulary;           // absolute path; empty with online_vocabulary
  // The run grew its words (LoopDetector::online) instead of reading a
  // vocabulary file, with these options (descriptor aside: `descriptor`).
  bool online_vocabulary = false;
  OnlineVocabularyOptions online_options;
  // detect-loops --resume-state: the state (absolute path) the run started
  // from and the frames it held; the record and loops.csv's indices start
  // after them, and re-running the record alone cannot reproduce the run.
  std::string resumed_from;
  std::size_t resumed_frames = 0;
  std::string descriptor;
  int max_features = 0;               // 0: the extractor's default
  std::string params_json;            // LoopDetectorParams::to_json()
  vision::ImageSourceOptions source;  // how the inputs were read (stride, ...)
  std::vector<FrameRecord> frames;
  // The first kDrawnLoops loops found; inliers in pixels of the files (Frame::scale undone).
  std::vector<LoopRecord> loops;
  std::vector<StageTiming> timing;  // kStageNames, in that order
  // The record's file (set by load()): what its content later fails on (an
  // unknown descriptor, parameters, inputs that changed) names it.
  std::string path;
  // The loops.csv written with the record: its size and CRC-32C, so that a
  // loops.csv replaced or edited after the run (or a run killed between the
  // two renames) is told from its own. Not known (false) in records written
  // before the key existed.
  bool knows_loops_csv = false;
  std::uint64_t loops_csv_bytes = 0;
  std::uint32_t loops_csv_crc32c = 0;

  static std::string path_for(const std::string& loops_csv) { return loops_csv + ".run.json"; }
  // Only a regular file of at most kMaxRunRecordBytes; FileError naming the
  // file for anything malformed.
  static LoopRun load(const std::string& path);
};

// Whether `loops_csv` is the file written with `run`, read from `run_path`:
// throws FileError naming `loops_csv` when its size or CRC-32C differs from
// what the record says; returns false, checking nothing, for a record that
// does not say (written before records named their loops.csv).
bool check_loops_csv_of_run(const LoopRun& run, const std::string& run_path,
                            const std::string& loops_csv);

// Writes loops.csv and its run record while the frames are processed, so
// that neither the record nor the memory it takes grows with more than the
// frames: each frame goes to the record at once; the detections (a CSV row
// each), the loops the report draws and the stage timings (six numbers a
// frame) wait for commit(). Both files are written to temporaries beside
// them and appear together at commit(), or not at all: without commit()
// (an exception, a full disk) the previous files stay as they were. A
// loops.csv written in place (/dev/null, /dev/stdout, a FIFO) has no record.
class LoopRunFiles {
 public:
  // Starts both files; `description` gives the provenance, inputs, vocabulary,
  // descriptor, max_features, params_json and source recorded (its frames,
  // loops and timing are not used). Throws FileError naming the file that
  // cannot be created.
  LoopRunFiles(const std::string& loops_csv, const LoopRun& description);
  LoopRunFiles(const LoopRunFiles&) = delete;
  LoopRunFiles& operator=(const LoopRunFiles&) = delete;
  ~LoopRunFiles();

  // The next frame of the run (frames must come in order).
  void add(const SequenceFrame& frame);
  // Writes the ends of both files and renames them into place. Throws
  // FileError naming the file that could not be written.
  void commit();

  std::size_t frames() const noexcept;
  const std::vector<Detection>& detections() const noexcept;
  // The loops the report draws: the first kDrawnLoops, kDrawnInliers inliers each.
  const std::vector<LoopRecord>& loops() const noexcept;
  const std::vector<StageTiming>& timing() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace binbow::loop
