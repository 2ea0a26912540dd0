// The loop room: binbow.LoopDetector, LoopResult, detect_loops and
// write_report (LoopDetectorParams: bind_params.cpp; GroundTruth and
// evaluate: bind_evaluation.cpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "binbow/loop/loop_detector.h"
#include "binbow/loop/report.h"
#include "binbow/loop/run_record.h"
#include "binbow/loop/sequence.h"
#include "binbow/loop/similarity.h"
#include "binbow/vision/features.h"
#include "binbow/vision/frame_pipeline.h"
#include "binding.h"
#include "core/output_path.h"

namespace binbow::python {
namespace {

using loop::LoopDetectorParams;

// --- Loop detection

std::vector<vision::Keypoint> keypoints_from_array(const py::array& array) {
  if (array.dtype().kind() != 'f' ||
      (array.dtype().itemsize() != 4 && array.dtype().itemsize() != 8))
    throw py::type_error("keypoints must be a float32 (or float64) array, got dtype " +
                         py::str(array.dtype()).cast<std::string>());
  if (array.ndim() != 2 || (array.shape(1) != 6 && array.shape(1) != 2))
    throw py::value_error(
        "keypoints must be (N, 6) as FeatureExtractor gives them (x, y, size, angle, "
        "response, octave) or (N, 2) (x, y); got shape " +
        shape_of(array));
  const auto rows = py::array_t<double, py::array::forcecast>::ensure(array);
  if (!rows) throw py::error_already_set();
  const auto r = rows.unchecked<2>();
  std::vector<vision::Keypoint> keypoints(static_cast<std::size_t>(r.shape(0)));
  for (py::ssize_t i = 0; i < r.shape(0); ++i) {
    vision::Keypoint& k = keypoints[static_cast<std::size_t>(i)];
    k.x = static_cast<float>(r(i, 0));
    k.y = static_cast<float>(r(i, 1));
    if (r.shape(1) == 6) {
      k.size = static_cast<float>(r(i, 2));
      k.angle = static_cast<float>(r(i, 3));
      k.response = static_cast<float>(r(i, 4));
      // Only a whole pyramid level is an octave (and converts to int safely).
      if (!(std::abs(r(i, 5)) <= 64) || r(i, 5) != std::floor(r(i, 5)))
        throw py::value_error("keypoints[" + std::to_string(i) + "] has octave " +
                              std::to_string(r(i, 5)) + ", not a pyramid level");
      k.octave = static_cast<int>(r(i, 5));
    }
  }
  return keypoints;
}

// cv2.KeyPoint objects (what cv2.ORB.detectAndCompute returns), by their attributes.
std::vector<vision::Keypoint> keypoints_from_opencv(const py::sequence& objects) {
  std::vector<vision::Keypoint> keypoints;
  keypoints.reserve(objects.size());
  for (const py::handle object : objects) {
    if (!py::hasattr(object, "pt"))
      throw py::type_error("keypoints must be an array or a sequence of cv2.KeyPoint, got a " +
                           type_name(object) + " in the sequence");
    const py::tuple pt = object.attr("pt");
    vision::Keypoint k;
    k.x = pt[0].cast<float>();
    k.y = pt[1].cast<float>();
    k.size = object.attr("size").cast<float>();
    k.angle = object.attr("angle").cast<float>();
    k.response = object.attr("response").cast<float>();
    k.octave = object.attr("octave").cast<int>();
    keypoints.push_back(k);
  }
  return keypoints;
}

std::vector<vision::Keypoint> to_keypoints(const py::handle& object, std::size_t rows) {
  std::vector<vision::Keypoint> keypoints;
  if (py::isinstance<py::array>(object))
    keypoints = keypoints_from_array(py::reinterpret_borrow<py::array>(object));
  else if (py::isinstance<py::list>(object) || py::isinstance<py::tuple>(object))
    keypoints = keypoints_from_opencv(py::reinterpret_borrow<py::sequence>(object));
  else if (!object.is_none())
    throw py::type_error(
        "keypoints must be a float32 (N, 6) or (N, 2) array, a sequence of cv2.KeyPoint or "
        "None, got " +
        type_name(object));
  for (std::size_t i = 0; i < keypoints.size(); ++i)
    if (!std::isfinite(keypoints[i].x) || !std::isfinite(keypoints[i].y))
      throw py::value_error("keypoints[" + std::to_string(i) + "] has a non-finite position");
  if (keypoints.size() != rows)
    throw py::value_error("keypoints has " + std::to_string(keypoints.size()) +
                          " rows but descriptors " + std::to_string(rows) +
                          ": one keypoint per descriptor");
  return keypoints;
}

// A frame id taken strictly: an int (or numpy integer), not a bool or a
// float; a negative one or one beyond the ids is a ValueError, as one never
// processed is (LoopDetector's InvalidArgument).
EntryId frame_id(const py::handle& object, const char* method) {
  if (PyBool_Check(object.ptr()) || !PyIndex_Check(object.ptr()))
    throw py::type_error(std::string("LoopDetector.") + method + ": frame must be an int, got " +
                         type_name(object));
  const auto value = py::reinterpret_steal<py::int_>(PyNumber_Index(object.ptr()));
  if (!value) throw py::error_already_set();
  int overflow = 0;
  const long long id = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
  if (overflow != 0 || id < 0 || id >= static_cast<long long>(kAllEntries))
    throw py::value_error(std::string("LoopDetector.") + method + ": no frame " +
                          py::repr(value).cast<std::string>());
  return static_cast<EntryId>(id);
}

// LoopDetector is used by one thread at a time; the Python object may be
// shared, so calls are serialised here rather than left to race.
class PythonLoopDetector {
 public:
  PythonLoopDetector(Vocabulary vocabulary, const LoopDetectorParams& params)
      : detector_(std::move(vocabulary), params),
        code_size_(detector_.database().vocabulary().code_size()) {}
  PythonLoopDetector(loop::LoopDetector detector, std::size_t code_size)
      : detector_(std::move(detector)), code_size_(code_size) {}
  // A saved state (.bbld): online without a vocabulary, else with the one it ran with.
  static std::unique_ptr<PythonLoopDetector> load(const Path& path,
                                                  const std::optional<Vocabulary>& vocabulary) {
    return adopt(vocabulary ? loop::LoopDetector::load(path.string(), *vocabulary)
                            : loop::LoopDetector::load(path.string()));
  }
  void save(const Path& path) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    detector_.save(path.string());
  }
  // Pickled as (the .bbld bytes, the vocabulary or None when online): a
  // fixed vocabulary is recorded in the bytes by checksum only.
  py::tuple state() const {
    std::vector<std::uint8_t> bytes;
    {
      py::gil_scoped_release release;
      const std::lock_guard<std::mutex> lock(mutex_);
      bytes = detector_.serialize();
    }
    return py::make_tuple(to_bytes(bytes), online() ? py::none() : py::cast(vocabulary()));
  }
  static std::unique_ptr<PythonLoopDetector> from_state(const py::tuple& state) {
    if (state.size() != 2 || !py::isinstance<py::bytes>(state[0]) ||
        !(state[1].is_none() || py::isinstance<Vocabulary>(state[1])))
      throw py::value_error("invalid pickled binbow.LoopDetector");
    const auto bytes = state[0].cast<py::bytes>();
    const auto [data, size] = bytes_of(bytes);
    const std::string name = "<pickled binbow.LoopDetector>";
    if (state[1].is_none()) {
      py::gil_scoped_release release;
      return adopt(loop::LoopDetector::deserialize(data, size, name));
    }
    Vocabulary vocabulary = state[1].cast<Vocabulary>();
    py::gil_scoped_release release;
    return adopt(loop::LoopDetector::deserialize(data, size, name, std::move(vocabulary)));
  }
  static std::unique_ptr<PythonLoopDetector> adopt(loop::LoopDetector detector) {
    const std::size_t code_size = detector.online_vocabulary() != nullptr
                                      ? detector.online_vocabulary()->code_size()
                                      : detector.database().vocabulary().code_size();
    return std::make_unique<PythonLoopDetector>(std::move(detector), code_size);
  }
  std::string repr() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    std::string text = "<binbow.LoopDetector with " + std::to_string(detector_.size()) + " images";
    if (detector_.forgotten_count() > 0)
      text += " (" + std::to_string(detector_.forgotten_count()) + " forgotten)";
    if (online())
      text += ", online vocabulary of " +
              std::to_string(detector_.online_vocabulary()->word_count()) + " words>";
    else
      text += ", vocabulary " + vocabulary().description() + ">";
    return text;
  }
  void set_label(const py::handle& frame, const std::string& label) {
    const EntryId id = frame_id(frame, "set_label");
    const std::lock_guard<std::mutex> lock(mutex_);
    detector_.set_label(id, label);
  }
  std::optional<std::string> label(const py::handle& frame) const {
    const EntryId id = frame_id(frame, "label");
    const std::lock_guard<std::mutex> lock(mutex_);
    std::string label = detector_.label(id);
    if (label.empty()) return std::nullopt;
    return label;
  }

  loop::SequenceFrame process(const py::object& keypoints, const py::object& descriptors) {
    const Descriptors d = to_descriptors(descriptors, "descriptors", code_size_);
    const std::vector<vision::Keypoint> points = to_keypoints(keypoints, d.view.rows);
    py::gil_scoped_release release;
    const std::lock_guard<std::mutex> lock(mutex_);
    loop::SequenceFrame frame;
    frame.result = detector_.process(Span<vision::Keypoint>(points.data(), points.size()), d.view);
    if (frame.result.detection()) {
      const Span<vision::Keypoint> match = detector_.keypoints(frame.result.match);
      for (const vision::Correspondence& c : frame.result.inliers)
        frame.inlier_points.push_back(
            {points[c.first].x, points[c.first].y, match[c.second].x, match[c.second].y});
    }
    return frame;
  }

  std::size_t size() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return detector_.size();
  }
  // The database may compact a segment: the GIL is released meanwhile.
  void forget(const py::handle& frame) {
    const EntryId id = frame_id(frame, "forget");
    py::gil_scoped_release release;
    const std::lock_guard<std::mutex> lock(mutex_);
    detector_.forget(id);
  }
  bool is_forgotten(const py::handle& frame) const {
    const EntryId id = frame_id(frame, "is_forgotten");
    const std::lock_guard<std::mutex> lock(mutex_);
    return detector_.is_forgotten(id);
  }
  std::size_t forgotten_count() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return detector_.forgotten_count();
  }
  std::size_t memory_usage() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return detector_.memory_usage();
  }
  void clear() {
    const std::lock_guard<std::mutex> lock(mutex_);
    detector_.clear();
  }
  // Both fixed at construction.
  const LoopDetectorParams& params() const { return detector_.params(); }
  const Vocabulary& vocabulary() const { return detector_.database().vocabulary(); }
  bool online() const { return detector_.online_vocabulary() != nullptr; }
  std::size_t word_count() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return online() ? detector_.online_vocabulary()->word_count()
                    : detector_.database().vocabulary().word_count();
  }

 private:
  loop::LoopDetector detector_;
  std::size_t code_size_;
  mutable std::mutex mutex_;
};

// OnlineVocabularyOptions from LoopDetector.online's keyword arguments.
OnlineVocabularyOptions online_options(const py::kwargs& options) {
  OnlineVocabularyOptions o;
  for (const auto& [key, value] : options) {
    const std::string name = key.cast<std::string>();
    if (name == "new_word_distance")
      o.new_word_distance = value.cast<double>();
    else if (name == "purge_after_images")
      o.purge_after_images = int_argument<std::uint32_t>(value, name);
    else if (name == "trees")
      o.trees = int_argument<std::uint32_t>(value, name);
    else if (name == "branching")
      o.branching = int_argument<std::uint32_t>(value, name);
    else if (name == "leaf_size")
      o.leaf_size = int_argument<std::uint32_t>(value, name);
    else if (name == "max_checks")
      o.max_checks = int_argument<std::uint32_t>(value, name);
    else if (name == "exact")
      o.exact = value.cast<bool>();
    else if (name == "seed")
      o.seed = int_argument<std::uint64_t>(value, name);
    else
      throw py::type_error(
          "LoopDetector.online: unknown vocabulary option '" + name +
          "' (new_word_distance, purge_after_images, trees, branching, leaf_size, max_checks, "
          "exact, seed)");
  }
  return o;
}

std::unique_ptr<PythonLoopDetector> online_detector(const py::object& descriptor,
                                                    const std::optional<LoopDetectorParams>& params,
                                                    const py::kwargs& options) {
  OnlineVocabularyOptions o = online_options(options);
  std::size_t code_size = 0;
  if (py::isinstance<py::str>(descriptor)) {
    o.descriptor = descriptor.cast<std::string>();
    code_size = vision::make_extractor(o.descriptor, 0)->code_size();
  } else if (PyLong_Check(descriptor.ptr()) && !PyBool_Check(descriptor.ptr())) {
    code_size = int_argument<std::size_t>(descriptor, "LoopDetector.online: descriptor size");
  } else {
    throw py::type_error(
        "LoopDetector.online: descriptor must be an extractor name (\"orb\", ...) or a "
        "descriptor size in bytes, got " +
        type_name(descriptor));
  }
  return std::make_unique<PythonLoopDetector>(
      loop::LoopDetector::online(code_size, std::move(o), params.value_or(LoopDetectorParams{})),
      code_size);
}

py::array_t<std::int64_t> inlier_array(const std::vector<vision::Correspondence>& inliers) {
  py::array_t<std::int64_t> out({static_cast<py::ssize_t>(inliers.size()), py::ssize_t{2}});
  auto rows = out.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < rows.shape(0); ++i) {
    rows(i, 0) = inliers[static_cast<std::size_t>(i)].first;
    rows(i, 1) = inliers[static_cast<std::size_t>(i)].second;
  }
  return out;
}

py::array_t<float> inlier_points_array(const std::vector<std::array<float, 4>>& points) {
  py::array_t<float> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{4}});
  auto rows = out.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < rows.shape(0); ++i)
    for (py::ssize_t j = 0; j < 4; ++j)
      rows(i, j) = points[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
  return out;
}

py::dict times_dict(const loop::SequenceFrame& frame) {
  const std::array<double, loop::kStageCount> ms = frame.stage_ms();
  py::dict out;
  for (std::size_t i = 0; i < loop::kStageCount; ++i) out[loop::kStageNames[i]] = ms[i];
  return out;
}

// An island exists once the candidates passed alpha and formed one.
bool has_island(const loop::LoopResult& r) {
  return r.status == loop::LoopStatus::kNoTemporalConsistency ||
         r.status == loop::LoopStatus::kNoGeometricConsistency || r.detection();
}

std::string result_repr(const loop::SequenceFrame& frame) {
  const loop::LoopResult& r = frame.result;
  std::string text = "<binbow.LoopResult query " + std::to_string(r.query);
  if (!frame.file.empty()) text += " (" + frame.file + ")";
  text += std::string(" ") + loop::to_string(r.status);
  if (r.has_candidate) {
    char numbers[96];
    std::snprintf(numbers, sizeof numbers, " match %u score %.4g normalised %.4g",
                  static_cast<unsigned>(r.match), r.score, r.normalised_score);
    text += numbers;
  }
  if (r.detection()) text += " inliers " + std::to_string(r.inliers.size());
  return text + ">";
}

// A LoopResult as plain Python values, for pickle (results saved, or sent to
// other processes): every field of the frame, in one fixed order.
py::tuple frame_state(const loop::SequenceFrame& frame) {
  const loop::LoopResult& r = frame.result;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> inliers;
  for (const vision::Correspondence& c : r.inliers) inliers.emplace_back(c.first, c.second);
  const loop::LoopStageTimes& t = r.times;
  return py::make_tuple(frame.file, frame.match_file, frame.features_ms, frame.inlier_points,
                        static_cast<int>(r.status), r.query, r.has_candidate, r.match, r.score,
                        r.normalisation_score, r.normalised_score, r.island_score, r.island_first,
                        r.island_last, r.consistent_queries, r.correspondences,
                        r.exhaustive_fallback_used, inliers,
                        std::array<double, 5>{t.transform_ms, t.query_ms, t.islands_ms,
                                              t.verification_ms, t.insertion_ms},
                        r.features, frame.unreadable, static_cast<int>(r.fit_evidence),
                        static_cast<int>(r.accepted_by), r.localised, r.localised_from);
}

loop::SequenceFrame frame_from_state(const py::tuple& state) {
  constexpr int kLastStatus = static_cast<int>(loop::LoopStatus::kNoGeometricConsistency);
  // 20 fields before `unreadable` was added, 21 before the fit's evidence and
  // what accepted the loop, 23 before localisation.
  if (state.size() != 20 && state.size() != 21 && state.size() != 23 && state.size() != 25)
    throw py::value_error("invalid pickled binbow.LoopResult");
  loop::SequenceFrame frame;
  frame.file = state[0].cast<std::string>();
  frame.match_file = state[1].cast<std::string>();
  frame.features_ms = state[2].cast<double>();
  frame.inlier_points = state[3].cast<std::vector<std::array<float, 4>>>();
  loop::LoopResult& r = frame.result;
  const int status = state[4].cast<int>();
  if (status < 0 || status > kLastStatus)
    throw py::value_error("invalid pickled binbow.LoopResult: status " + std::to_string(status));
  r.status = static_cast<loop::LoopStatus>(status);
  r.query = state[5].cast<EntryId>();
  r.has_candidate = state[6].cast<bool>();
  r.match = state[7].cast<EntryId>();
  r.score = state[8].cast<double>();
  r.normalisation_score = state[9].cast<double>();
  r.normalised_score = state[10].cast<double>();
  r.island_score = state[11].cast<double>();
  r.island_first = state[12].cast<EntryId>();
  r.island_last = state[13].cast<EntryId>();
  r.consistent_queries = state[14].cast<int>();
  r.correspondences = state[15].cast<std::size_t>();
  r.exhaustive_fallback_used = state[16].cast<bool>();
  for (const auto& [first, second] :
       state[17].cast<std::vector<std::pair<std::uint32_t, std::uint32_t>>>())
    r.inliers.push_back({first, second});
  const auto ms = state[18].cast<std::array<double, 5>>();
  r.times = {ms[0], ms[1], ms[2], ms[3], ms[4]};
  r.features = state[19].cast<std::size_t>();
  if (state.size() > 20) frame.unreadable = state[20].cast<std::string>();
  if (state.size() > 21) {
    const int evidence = state[21].cast<int>(), accepted_by = state[22].cast<int>();
    if (evidence < 0 || evidence > static_cast<int>(vision::FitEvidence::kDegenerate) ||
        accepted_by < 0 || accepted_by > static_cast<int>(loop::LoopEvidence::kNeighbour))
      throw py::value_error("invalid pickled binbow.LoopResult: evidence " +
                            std::to_string(evidence) + ", accepted by " +
                            std::to_string(accepted_by));
    r.fit_evidence = static_cast<vision::FitEvidence>(evidence);
    r.accepted_by = static_cast<loop::LoopEvidence>(accepted_by);
  }
  if (state.size() > 23) {
    r.localised = state[23].cast<bool>();
    r.localised_from = state[24].cast<EntryId>();
  }
  return frame;
}

void bind_detection(py::module_& m) {
  py::class_<loop::SequenceFrame>(
      m, "LoopResult",
      "The outcome of one frame of loop detection (LoopDetector.process,\n"
      "detect_loops).")
      .def_readonly("file", &loop::SequenceFrame::file,
                    "The frame's name (file path, or \"video.mp4#N\"); \"\" from process().")
      .def_readonly("match_file", &loop::SequenceFrame::match_file,
                    "Detections of detect_loops: the loop's earlier frame's name; \"\" otherwise.")
      .def_property_readonly(
          "status",
          [](const loop::SequenceFrame& f) {
            return f.unreadable.empty() ? loop::to_string(f.result.status)
                                        : loop::kUnreadableFrameStatus;
          },
          "Why the frame did or did not close a loop, as the CLI names it: \"loop-detected\",\n"
          "\"no-database-results\", \"low-normalisation-score\", \"low-scores\", \"no-islands\",\n"
          "\"no-temporal-consistency\", \"no-geometric-consistency\"; \"unreadable\" for a frame\n"
          "detect_loops(skip_unreadable=True) could not read.")
      .def_readonly("unreadable", &loop::SequenceFrame::unreadable,
                    "Why detect_loops(skip_unreadable=True) could not read the frame (it kept\n"
                    "its index, without features); \"\" for a frame read.")
      .def_property_readonly(
          "detection", [](const loop::SequenceFrame& f) { return f.result.detection(); },
          "Whether a loop was detected.")
      .def_property_readonly(
          "query", [](const loop::SequenceFrame& f) { return f.result.query; },
          "The frame's 0-based index in the sequence (its entry id).")
      .def_property_readonly(
          "match",
          [](const loop::SequenceFrame& f) -> std::optional<EntryId> {
            if (!f.result.has_candidate) return std::nullopt;
            return f.result.match;
          },
          "The loop's earlier frame when detected, otherwise the best candidate so far;\n"
          "None when there was no candidate.")
      .def_property_readonly(
          "score", [](const loop::SequenceFrame& f) { return f.result.score; },
          "Similarity s(v_t, v_match) of the frame and the match.")
      .def_property_readonly(
          "normalisation_score",
          [](const loop::SequenceFrame& f) { return f.result.normalisation_score; },
          "s(v_t, v_t-1), what the score is divided by; 0 before the first query.")
      .def_property_readonly(
          "normalised_score",
          [](const loop::SequenceFrame& f) { return f.result.normalised_score; },
          "eta of the match (the score when normalisation is off); loops.csv's score.")
      .def_property_readonly(
          "island",
          [](const loop::SequenceFrame& f) -> std::optional<std::pair<EntryId, EntryId>> {
            if (!has_island(f.result)) return std::nullopt;
            return std::make_pair(f.result.island_first, f.result.island_last);
          },
          "(first, last) frames of the best island, None when no island formed.")
      .def_property_readonly(
          "island_score", [](const loop::SequenceFrame& f) { return f.result.island_score; },
          "H, the sum of eta over the best island (0 without one).")
      .def_property_readonly(
          "consistent_queries",
          [](const loop::SequenceFrame& f) { return f.result.consistent_queries; },
          "Consecutive queries agreeing on the island so far, this one included.")
      .def_property_readonly(
          "correspondences", [](const loop::SequenceFrame& f) { return f.result.correspondences; },
          "Putative correspondences given to RANSAC.")
      .def_property_readonly(
          "features", [](const loop::SequenceFrame& f) { return f.result.features; },
          "Keypoints of the image (0: it can match nothing).")
      .def_property_readonly(
          "exhaustive_fallback_used",
          [](const loop::SequenceFrame& f) { return f.result.exhaustive_fallback_used; },
          "Whether the geometric check retried with exhaustive matching.")
      .def_property_readonly(
          "fit_evidence",
          [](const loop::SequenceFrame& f) { return vision::to_string(f.result.fit_evidence); },
          "What the geometric check's inliers determine: \"fundamental\", \"homography\",\n"
          "\"degenerate\" (points near a line, on one patch, too few: no evidence), or \"none\".")
      .def_property_readonly(
          "accepted_by",
          [](const loop::SequenceFrame& f) { return loop::to_string(f.result.accepted_by); },
          "What accepted the loop: \"strong-fit\", \"strong-fit-alone\" (before temporal\n"
          "consistency), \"near-previous-loop\", \"revisit-pace\",\n"
          "\"neighbour\", \"unchecked\" (no geometric check), or \"none\" (no loop).")
      .def_property_readonly(
          "localised_from",
          [](const loop::SequenceFrame& f) -> std::optional<EntryId> {
            if (!f.result.localised) return std::nullopt;
            return f.result.localised_from;
          },
          "The entry of the island first accepted, when the loop moved from it to `match`\n"
          "(LoopDetectorParams.localise_in_island); None otherwise.")
      .def_property_readonly(
          "inliers", [](const loop::SequenceFrame& f) { return inlier_array(f.result.inliers); },
          "RANSAC inliers as an int64 (M, 2) array: feature of the frame, feature of the match\n"
          "(rows of their keypoints and descriptors).")
      .def_property_readonly(
          "inlier_points",
          [](const loop::SequenceFrame& f) { return inlier_points_array(f.inlier_points); },
          "Detections: float32 (M, 4) rows x, y in the frame, x, y in the match, in pixels of\n"
          "the files (detect_loops) or of the keypoints given (process); empty otherwise.")
      .def_property_readonly("times", &times_dict,
                             "Milliseconds of each stage: features (0 from process(), which gets\n"
                             "them extracted), transform, query, islands, verification, "
                             "insertion.")
      .def("__repr__", &result_repr, "Status, match and scores as text.")
      .def(py::pickle(&frame_state, &frame_from_state));

  py::class_<PythonLoopDetector>(
      m, "LoopDetector",
      "The paper's loop detector over a sequence of images (Galvez-Lopez & Tardos 2012,\n"
      "Section V): process() each image's features in order. Calls from several threads\n"
      "are serialised; use one detector per sequence.")
      .def(py::init([](Vocabulary vocabulary, const std::optional<LoopDetectorParams>& params) {
             return std::make_unique<PythonLoopDetector>(std::move(vocabulary),
                                                         params.value_or(LoopDetectorParams{}));
           }),
           py::arg("vocabulary"), py::arg("params") = py::none(),
           "A detector over the vocabulary, with params (the paper's defaults when None).")
      .def("process", &PythonLoopDetector::process, py::arg("keypoints"), py::arg("descriptors"),
           "Add the next image and look for a loop with the earlier ones; returns a LoopResult.\n\n"
           "keypoints: float32 (N, 6) as FeatureExtractor.extract gives them, or (N, 2) x, y\n"
           "(float64 too), or a sequence of cv2.KeyPoint; descriptors: uint8 (N, code_size),\n"
           "row i describing keypoint i. An image without features: descriptors None and\n"
           "keypoints None or empty (it is added, and can match nothing).")
      .def("__len__", &PythonLoopDetector::size, "Images processed.")
      .def("__repr__", &PythonLoopDetector::repr, "Images processed and vocabulary as text.")
      .def("set_label", &PythonLoopDetector::set_label, py::arg("frame"), py::arg("label"),
           "Name a processed frame (e.g. its file), or with \"\" remove its name; saved with\n"
           "the state. ValueError for a frame never processed or forgotten.")
      .def("label", &PythonLoopDetector::label, py::arg("frame"),
           "The frame's name, None if it has none (ValueError as set_label).")
      .def(py::pickle([](const PythonLoopDetector& self) { return self.state(); },
                      &PythonLoopDetector::from_state))
      .def("clear", &PythonLoopDetector::clear, "Forget every image; the next one is query 0.")
      .def("forget", &PythonLoopDetector::forget, py::arg("frame"),
           "Keyframe culling: never propose this frame again (as a match, in an island or to\n"
           "the geometric check) and free its features and its database entry. Frame ids\n"
           "are not reused and len() still counts it; the temporal state it took part in\n"
           "(the next frame's normalisation, the consistency chain) is kept. Forgetting a\n"
           "forgotten frame does nothing; a frame never processed raises ValueError.\n"
           "save() keeps it forgotten.")
      .def("is_forgotten", &PythonLoopDetector::is_forgotten, py::arg("frame"),
           "Whether forget() was called for this frame (ValueError if never processed).")
      .def_property_readonly("forgotten_count", &PythonLoopDetector::forgotten_count,
                             "Frames forgotten so far (len() counts them too).")
      .def_property_readonly("memory_usage", &PythonLoopDetector::memory_usage,
                             "Bytes of heap memory held: database, kept features, online words.")
      .def_property_readonly("params", &PythonLoopDetector::params,
                             "The detector's parameters (a copy).")
      .def_static("online", &online_detector, py::arg("descriptor"), py::arg("params") = py::none(),
                  "A detector with no pre-trained vocabulary: its words grow from the images\n"
                  "themselves (docs/online-vocabulary.md). descriptor: an extractor\n"
                  "name (\"orb\", \"brief\", ...) or the descriptor size in bytes; params: a\n"
                  "LoopDetectorParams or None; keyword arguments set the online vocabulary's\n"
                  "options: new_word_distance, purge_after_images, trees, branching, leaf_size,\n"
                  "max_checks, exact, seed.")
      .def_property_readonly("vocabulary", &PythonLoopDetector::vocabulary,
                             "The detector's vocabulary (empty for an online detector).")
      .def_property_readonly("is_online", &PythonLoopDetector::online,
                             "Whether the words grow from the images (LoopDetector.online).")
      .def_property_readonly("word_count", &PythonLoopDetector::word_count,
                             "Words of the vocabulary (the live online words so far).")
      .def("save", &PythonLoopDetector::save, py::arg("path"),
           py::call_guard<py::gil_scoped_release>(),
           "Save the whole state as .bbld (atomically), to resume later with\n"
           "LoopDetector.load: the images so far, the temporal state and an online\n"
           "detector's words; a fixed vocabulary is recorded by checksum, not embedded.")
      .def_static("load", &PythonLoopDetector::load, py::arg("path"),
                  py::arg("vocabulary") = py::none(), py::call_guard<py::gil_scoped_release>(),
                  "Resume a detector saved by save(): vocabulary None for an online detector,\n"
                  "else the vocabulary it ran with (another one raises OSError). The next\n"
                  "image continues its numbering and gets the results the saved detector\n"
                  "would have given (see docs/online-vocabulary.md for online approximate\n"
                  "search).");
}

// --- Sequences: detect_loops and write_report, faces of loop::SequenceDetector
// and loop::make_loop_report.

// The bounds ImageSource checks, as ValueErrors naming the keyword and
// before the narrowing casts.
vision::ImageSourceOptions source_options(const py::object& stride, const py::object& max_width,
                                          double video_fps, bool skip_unreadable) {
  vision::ImageSourceOptions source;
  source.stride = int_argument<std::size_t>(stride, "stride", 1, vision::kMaxStride);
  source.max_width = int_argument<int>(max_width, "max_width", 0, vision::kMaxFrameWidth);
  if (!(video_fps >= 0 && video_fps <= vision::kMaxVideoFps))
    throw py::value_error("video_fps must be in [0, " +
                          std::to_string(static_cast<int>(vision::kMaxVideoFps)) + "], got " +
                          std::to_string(video_fps));
  source.video_fps = video_fps;
  source.skip_unreadable = skip_unreadable;
  return source;
}

// binbow.detect_loops (binbow/__init__.py) after its arguments are resolved:
// `descriptor` a name or a FeatureExtractor, `params` a LoopDetectorParams, a
// parameter file's path or None, `progress` None or a callable(done, total).
std::tuple<std::vector<loop::SequenceFrame>, LoopDetectorParams, loop::SimilarityMatrix>
detect_loops(const std::vector<std::string>& inputs, std::optional<Vocabulary> vocabulary,
             const py::object& descriptor, const py::object& max_features, const py::object& params,
             const py::object& stride, const py::object& max_width, double video_fps,
             const py::object& progress, bool online, const std::string& resume_state,
             const std::string& save_state, bool skip_unreadable, const py::object& threads) {
  loop::SequenceOptions options;
  options.source = source_options(stride, max_width, video_fps, skip_unreadable);
  options.threads = int_argument<unsigned>(threads, "threads", 0, vision::kMaxPipelineThreads);
  if (const auto extractor = extractor_of(descriptor)) {
    if (!max_features.is_none())
      throw py::value_error(
          "max_features applies to a descriptor name; a FeatureExtractor has its own");
    options.extractor = extractor;
  } else if (py::isinstance<py::str>(descriptor)) {
    options.descriptor = descriptor.cast<std::string>();
    if (!max_features.is_none())
      options.max_features = int_argument<int>(max_features, "max_features", 1, 1000000);
  } else {
    throw py::type_error("descriptor must be a name (\"orb\", ...) or a FeatureExtractor, got " +
                         type_name(descriptor));
  }
  std::optional<LoopDetectorParams> given;
  if (py::isinstance<LoopDetectorParams>(params))
    given = params.cast<LoopDetectorParams>();
  else if (!params.is_none())
    options.params_file = params.cast<std::string>();

  std::unique_ptr<loop::SequenceDetector> sequence;
  {
    py::gil_scoped_release release;
    // Before the run: a folder that cannot be written fails now, not after it.
    if (!save_state.empty()) detail::prepare_output_file(save_state);
    if (!resume_state.empty())
      sequence = std::make_unique<loop::SequenceDetector>(
          inputs,
          online ? loop::LoopDetector::load(resume_state)
                 : loop::LoopDetector::load(resume_state,
                                            std::move(vocabulary).value_or(Vocabulary())),
          options);
    else if (online)
      sequence = given ? std::make_unique<loop::SequenceDetector>(inputs, OnlineVocabularyOptions{},
                                                                  options, *given)
                       : std::make_unique<loop::SequenceDetector>(inputs, OnlineVocabularyOptions{},
                                                                  options);
    else
      sequence = given ? std::make_unique<loop::SequenceDetector>(
                             inputs, std::move(vocabulary).value_or(Vocabulary()), options, *given)
                       : std::make_unique<loop::SequenceDetector>(
                             inputs, std::move(vocabulary).value_or(Vocabulary()), options);
  }
  const long long known = sequence->size();
  const py::object total = known >= 0 ? py::object(py::int_(known)) : py::object(py::none());
  std::vector<loop::SequenceFrame> frames;
  while (true) {
    loop::SequenceFrame frame;
    bool more = false;
    {
      py::gil_scoped_release release;
      more = sequence->next(frame);
    }
    if (!more) break;
    frames.push_back(std::move(frame));
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C stops the run
    if (!progress.is_none()) progress(frames.size(), total);
  }
  loop::SimilarityMatrix similarity;
  {
    py::gil_scoped_release release;
    if (!save_state.empty()) sequence->detector().save(save_state);
    if (sequence->params().geometric_check != loop::GeometricCheck::kNone)
      similarity = loop::similarity_matrix(sequence->detector());
  }
  return {std::move(frames), sequence->params(), std::move(similarity)};
}

std::vector<loop::SequenceFrame> frames_of(const py::handle& results) {
  if (!py::isinstance<py::iterable>(results) || py::isinstance<py::str>(results))
    throw py::type_error("results must be a list of LoopResult, got " + type_name(results));
  std::vector<loop::SequenceFrame> frames;
  for (const py::handle item : results) {
    if (!py::isinstance<loop::SequenceFrame>(item))
      throw py::type_error("results must hold LoopResult objects, got " + type_name(item));
    frames.push_back(item.cast<const loop::SequenceFrame&>());
  }
  return frames;
}

// Who writes a report from Python: this binbow, now (UTC), and the
// interpreter's command line as a shell reads it back (none when sys.argv
// is missing or empty, as in an embedded interpreter).
loop::Provenance python_provenance() {
  loop::Provenance provenance;
  provenance.binbow_version = BINBOW_VERSION;
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &utc);
  provenance.date = date;
  const py::module_ sys = py::module_::import("sys");
  if (py::hasattr(sys, "argv") && py::len(sys.attr("argv")) > 0) {
    py::list command;
    command.append(sys.attr("executable"));
    for (const py::handle argument : sys.attr("argv")) command.append(argument);
    provenance.command = py::module_::import("shlex").attr("join")(command).cast<std::string>();
  }
  return provenance;
}

// The CLI's detect-loops report: make_loop_report's page with the facts the
// CLI shows (inputs, frequency, vocabulary, descriptor) where the run knew them.
std::string write_report(const Path& folder, const py::object& results,
                         const loop::GroundTruth* truth,
                         const std::optional<LoopDetectorParams>& params, const std::string& inputs,
                         const std::string& vocabulary, const std::string& descriptor,
                         const loop::SimilarityMatrix* similarity) {
  const std::vector<loop::SequenceFrame> frames = frames_of(results);
  if (similarity != nullptr && !similarity->empty() && similarity->frames != frames.size())
    throw py::value_error("the similarity matrix has " + std::to_string(similarity->frames) +
                          " frames but results has " + std::to_string(frames.size()));
  const loop::Provenance provenance = python_provenance();
  py::gil_scoped_release release;
  loop::LoopReport report =
      similarity != nullptr
          ? loop::make_loop_report(frames, params.value_or(LoopDetectorParams{}), truth,
                                   *similarity)
          : loop::make_loop_report(frames, params.value_or(LoopDetectorParams{}), truth);
  if (params) {
    char hertz[32];
    std::snprintf(hertz, sizeof hertz, "%g Hz", params->frequency);
    report.facts.emplace_back("frequency", hertz);
  } else {
    report.params_json.clear();  // not known: not shown as the defaults
  }
  report.provenance = provenance;
  if (!inputs.empty()) report.facts.insert(report.facts.begin(), {"inputs", inputs});
  if (!vocabulary.empty()) report.facts.emplace_back("vocabulary", vocabulary);
  if (!descriptor.empty()) report.facts.emplace_back("descriptor", descriptor);
  return loop::write_loop_report(folder.string(), report);
}

void bind_similarity(py::module_& m) {
  py::class_<loop::SimilarityMatrix>(
      m, "SimilarityMatrix",
      "s(v_i, v_j) of every image i with every earlier image j, the figure of\n"
      "loop-closure papers; long runs binned (bin x bin frames a cell, the highest\n"
      "score of the cell). detect_loops' results carry it as .similarity.")
      .def_property_readonly(
          "scores",
          [](const loop::SimilarityMatrix& matrix) {
            py::array_t<float> scores({matrix.cells, matrix.cells});
            std::copy(matrix.scores.begin(), matrix.scores.end(), scores.mutable_data());
            return scores;
          },
          "float32 (cells, cells): row = query cell, column = earlier cell; upper triangle 0.")
      .def_readonly("frames", &loop::SimilarityMatrix::frames, "Images of the sequence.")
      .def_readonly("bin", &loop::SimilarityMatrix::bin, "Frames per cell side.")
      .def_readonly("cells", &loop::SimilarityMatrix::cells, "Cells per side.")
      .def_readonly("every_query", &loop::SimilarityMatrix::every_query,
                    "Whether every query row was scored (else every bin-th one).")
      .def(
          "__repr__",
          [](const loop::SimilarityMatrix& matrix) {
            return "SimilarityMatrix(frames=" + std::to_string(matrix.frames) +
                   ", bin=" + std::to_string(matrix.bin) +
                   ", cells=" + std::to_string(matrix.cells) + ")";
          },
          "Frames, bin and cells as text.")
      .def(py::pickle(
          [](const loop::SimilarityMatrix& matrix) {
            return py::make_tuple(matrix.frames, matrix.bin, matrix.cells, matrix.every_query,
                                  py::bytes(reinterpret_cast<const char*>(matrix.scores.data()),
                                            matrix.scores.size() * sizeof(float)));
          },
          [](const py::tuple& state) {
            if (state.size() != 5) throw py::value_error("not a pickled SimilarityMatrix");
            loop::SimilarityMatrix matrix;
            matrix.frames = state[0].cast<std::size_t>();
            matrix.bin = state[1].cast<std::size_t>();
            matrix.cells = state[2].cast<std::size_t>();
            matrix.every_query = state[3].cast<bool>();
            const std::string bytes = state[4].cast<std::string>();
            if (matrix.cells > loop::kMaxSimilarityCells || matrix.bin == 0 ||
                bytes.size() != matrix.cells * matrix.cells * sizeof(float) ||
                matrix.cells != (matrix.frames + matrix.bin - 1) / matrix.bin)
              throw py::value_error("not a pickled SimilarityMatrix: inconsistent sizes");
            matrix.scores.resize(matrix.cells * matrix.cells);
            std::memcpy(matrix.scores.data(), bytes.data(), bytes.size());
            return matrix;
          }));
}

void bind_sequences(py::module_& m) {
  m.def("_detect_loops", &detect_loops, py::arg("inputs"), py::arg("vocabulary"),
        py::arg("descriptor"), py::arg("max_features"), py::arg("params"), py::arg("stride"),
        py::arg("max_width"), py::arg("video_fps"), py::arg("progress"), py::arg("online") = false,
        py::arg("resume_state") = "", py::arg("save_state") = "",
        py::arg("skip_unreadable") = false, py::arg("threads") = 0,
        "binbow.detect_loops once its arguments are resolved (use that): the frames and\n"
        "the parameters used.");
  m.def(
      "_saved_state",
      [](const std::string& path) {
        loop::LoopDetectorFileInfo saved;
        {
          py::gil_scoped_release release;
          saved = loop::LoopDetector::inspect(path);
        }
        return py::make_tuple(saved.online, saved.descriptor, saved.frames);
      },
      py::arg("path"),
      "binbow.detect_loops' view of a state to resume: (online, descriptor, frames).");
  m.def("_write_report", &write_report, py::arg("folder"), py::arg("results"),
        py::arg("ground_truth"), py::arg("params"), py::arg("inputs"), py::arg("vocabulary"),
        py::arg("descriptor"), py::arg("similarity"),
        "binbow.write_report with the run's facts resolved (use that).");
}

}  // namespace

void bind_loop(py::module_& m) {
  bind_detection(m);
  bind_similarity(m);
  bind_sequences(m);
}

}  // namespace binbow::python
