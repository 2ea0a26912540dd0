// The HTML report of detect-loops and evaluate: one self-contained page
// (inline CSS, SVG and base64 images; nothing fetched) with the
// precision–recall curve and its sweep table, the similarity matrix with the
// ground truth and the detections over it, every missed ground-truth loop
// and why, every false loop and miss explained stage by stage with the two
// frames and their correspondences (explanation.h), the parameters, the
// per-stage timing, the table of detections
// and, for each loop, the two images side by side with the inlier
// correspondences drawn.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/explanation.h"
#include "binbow/loop/misses.h"
#include "binbow/loop/provenance.h"
#include "binbow/loop/run_record.h"
#include "binbow/loop/sequence.h"
#include "binbow/loop/similarity.h"

namespace binbow::loop {

struct ReportLoop {
  Detection detection;
  // Query x, y, match x, y (pixels of the files); kDrawnInliers of them are drawn.
  std::vector<std::array<float, 4>> inliers;
  int verdict = -1;  // 1 true positive, 0 false positive, -1 unknown
};

struct LoopReport {
  std::string title;
  // Shown under the title: the binbow, date and command that wrote the page
  // (id 'provenance') and, for an evaluation, those of the detection run it
  // judges, from its run record (id 'run-provenance'). Empty: not shown.
  Provenance provenance;
  Provenance run_provenance;
  std::vector<std::pair<std::string, std::string>> facts;  // shown as a two-column table
  std::string params_json;                                 // empty: not known
  std::vector<StageTiming> timing;                         // empty: not measured
  std::vector<ReportLoop> loops;
  bool has_result = false;  // precision and recall against ground truth
  PrecisionRecall result;
  std::vector<PrCurvePoint> curve;  // empty: no curve
  std::string curve_parameter;      // what the curve sweeps ("alpha", "score")
  double recall_at_full_precision = 0;
  // With a ground truth (has_result): the missed loops (missed_loops()),
  // listed in the "Missed loops" table (id 'missed', a row id 'missed-<query>' each).
  std::vector<MissedLoop> missed;
  // Drawn as similarity.png (written beside index.html and embedded) with
  // `truth` and the loops over it; empty: no figure.
  SimilarityMatrix similarity;
  GroundTruth truth;  // for the figure; frames() == 0: not known
  // Every false loop and every miss explained (explain_run), shown in the
  // "Why" section (id 'explained'): a table row each ('explain-row-<query>'),
  // and for the first kExplainedPictures a figure ('explain-<query>') with the
  // two images, inliers and rejected correspondences drawn, and every
  // stage's numbers. has_explanations false: no section (no run to re-run).
  bool has_explanations = false;
  std::vector<LoopExplanation> explanations;
  std::string explanations_note;  // shown above them when not empty
};

// Explained cases drawn with pictures; the others are table rows, so that
// the page stays small (each picture is ~50–100 KB).
inline constexpr std::size_t kExplainedPictures = 40;

// Writes DIRECTORY/index.html (creating the directory), atomically, and
// DIRECTORY/similarity.png when the report has a similarity matrix.
// Returns the page's path. Images that cannot be read are reported as such.
std::string write_loop_report(const std::string& directory, const LoopReport& report);

// The report of a sequence run in memory (detect_sequence): its detections
// with their inliers, the stage timings and the parameters; with a ground
// truth, each detection's verdict and precision and recall too.
LoopReport make_loop_report(const std::vector<SequenceFrame>& frames,
                            const LoopDetectorParams& params, const GroundTruth* truth = nullptr);
// The same with the similarity matrix of the sequence (similarity_matrix() of
// the SequenceDetector's detector, or of the frames' features) for the figure.
LoopReport make_loop_report(const std::vector<SequenceFrame>& frames,
                            const LoopDetectorParams& params, const GroundTruth* truth,
                            const SimilarityMatrix& similarity);

// The similarity matrix drawn as an image with axes, a colour scale and a
// legend: scores in grey, ground-truth cells in blue, true loops green, false
// loops red, missed ground-truth loops orange. PNG bytes.
std::vector<unsigned char> similarity_png(const LoopReport& report);

}  // namespace binbow::loop
