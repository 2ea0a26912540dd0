// The loop room: binbow.LoopDetectorParams, LoopDetector, LoopResult,
// GroundTruth and evaluate.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <climits>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/evaluation.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/loop/report.h"
#include "binbow/loop/sequence.h"
#include "binbow/vision/features.h"
#include "binding.h"

namespace binbow::python {
namespace {

using loop::LoopDetectorParams;

// --- Python values checked as the parameter file's values are: a count is an
// int (not a bool, not 2.5), a switch a bool, a threshold a real number.

bool is_bool(const py::handle& value) {
  return PyBool_Check(value.ptr()) ||
         py::isinstance(value, py::module_::import("numpy").attr("bool_"));
}

bool is_integer(const py::handle& value) {
  return !is_bool(value) && PyIndex_Check(value.ptr());
}

bool is_real(const py::handle& value) {
  return !is_bool(value) && (PyFloat_Check(value.ptr()) || PyIndex_Check(value.ptr()) ||
                             py::isinstance(value, py::module_::import("numpy").attr("floating")));
}

// One field of LoopDetectorParams as a Python property.
struct Field {
  const char* name;
  const char* doc;
  std::function<py::object(const LoopDetectorParams&)> get;
  // Sets the field of `p` from a checked Python value (validate() comes after).
  std::function<void(LoopDetectorParams&, const py::handle&)> set;
};

Field int_field(const char* name, int LoopDetectorParams::*member, const char* doc) {
  return {name, doc, [member](const LoopDetectorParams& p) { return py::int_(p.*member); },
          [name, member](LoopDetectorParams& p, const py::handle& value) {
            if (!is_integer(value))
              throw py::type_error(std::string("loop detector parameter ") + name +
                                   " must be an int, got " + type_name(value));
            const auto number = py::int_(py::reinterpret_borrow<py::object>(value));
            long long x = 0;
            try {
              x = number.cast<long long>();
            } catch (const py::cast_error&) {
              x = LLONG_MAX;  // beyond long long: out of range below
            }
            if (x < INT_MIN || x > INT_MAX)
              throw py::value_error(std::string("loop detector parameter ") + name +
                                    " is out of range, got " +
                                    py::repr(number).cast<std::string>());
            p.*member = static_cast<int>(x);
          }};
}

Field real_field(const char* name, double LoopDetectorParams::*member, const char* doc) {
  return {name, doc, [member](const LoopDetectorParams& p) { return py::float_(p.*member); },
          [name, member](LoopDetectorParams& p, const py::handle& value) {
            if (!is_real(value))
              throw py::type_error(std::string("loop detector parameter ") + name +
                                   " must be a real number, got " + type_name(value));
            p.*member = py::float_(py::reinterpret_borrow<py::object>(value)).cast<double>();
          }};
}

Field bool_field(const char* name, bool LoopDetectorParams::*member, const char* doc) {
  return {name, doc, [member](const LoopDetectorParams& p) { return py::bool_(p.*member); },
          [name, member](LoopDetectorParams& p, const py::handle& value) {
            if (!is_bool(value))
              throw py::type_error(std::string("loop detector parameter ") + name +
                                   " must be a bool, got " + type_name(value));
            p.*member = value.cast<bool>();
          }};
}

// Every field, in the order of loop_detector.h and of to_json(); a test
// checks that the keys are the library's.
const std::vector<Field>& fields() {
  using P = LoopDetectorParams;
  static const std::vector<Field> table = {
      real_field("frequency", &P::frequency,
                 "Images per second the parameters were derived for, (0, 10000] (informative;\n"
                 "for_frequency and the keyword frequency= scale the frame counts to it)."),
      bool_field("use_normalised_score", &P::use_normalised_score,
                 "Compare the normalised score eta instead of the raw score with alpha."),
      real_field("alpha", &P::alpha, "Minimum eta (or raw score) of a candidate, [0, 1000]."),
      real_field("min_normalisation_score", &P::min_normalisation_score,
                 "Frames whose score with the previous frame is below this are skipped,\n"
                 "[0, 1000]."),
      int_field("dislocal", &P::dislocal,
                "Candidates of image t are images j < t - dislocal (20 f), [0, 1e6]."),
      int_field("max_db_results", &P::max_db_results,
                "Candidates taken from each database query (50 f), [1, 1e6]."),
      int_field("max_intra_island_gap", &P::max_intra_island_gap,
                "Entries closer than this join one island (3 f), [1, 1e6]."),
      int_field("min_matches_per_island", &P::min_matches_per_island,
                "Minimum island length (f), [1, 1e6]."),
      int_field("k", &P::k, "Consistent previous queries needed, [0, 1000]."),
      int_field("max_distance_between_islands", &P::max_distance_between_islands,
                "Islands of consecutive queries this far apart still agree (3 f), [0, 1e6]."),
      int_field("max_distance_between_queries", &P::max_distance_between_queries,
                "Queries further apart break the chain (2 f), [1, 1e6]."),
      Field{"geometric_check",
            "How correspondences for the fundamental matrix are found: \"direct-index\"\n"
            "(the paper's), \"exhaustive\" or \"none\" (no geometric check).",
            [](const P& p) { return py::str(loop::to_string(p.geometric_check)); },
            [](P& p, const py::handle& value) {
              if (!py::isinstance<py::str>(value))
                throw py::type_error("loop detector parameter geometric_check must be a str, got " +
                                     type_name(value));
              p.geometric_check = loop::parse_geometric_check(value.cast<std::string>());
            }},
      int_field("direct_index_levels", &P::direct_index_levels,
                "Direct index this many levels above the words, [0, 16]."),
      bool_field("exhaustive_fallback", &P::exhaustive_fallback,
                 "Retry with exhaustive matching when the direct index finds no fundamental\n"
                 "matrix (binbow's addition)."),
      int_field("max_verified_entries", &P::max_verified_entries,
                "Entries of the best island checked geometrically, best first, [1, 10]."),
      real_field("max_neighbor_ratio", &P::max_neighbor_ratio,
                 "Nearest-neighbour ratio test of correspondences, (0, 1]."),
      real_field("max_match_distance", &P::max_match_distance,
                 "Largest Hamming distance of a correspondence, as a fraction of the bits,\n"
                 "[0, 1]."),
      bool_field("accept_single_candidate", &P::accept_single_candidate,
                 "Accept a correspondence without a second neighbour (DLoopDetector does)."),
      int_field("min_inliers", &P::min_inliers,
                "Minimum RANSAC inliers of the fundamental matrix, [8, 10000]."),
      real_field("max_reprojection_error", &P::max_reprojection_error,
                 "RANSAC threshold in pixels, [0.1, 100]."),
      real_field("ransac_confidence", &P::ransac_confidence, "RANSAC confidence, (0, 1)."),
      int_field("max_ransac_iterations", &P::max_ransac_iterations,
                "RANSAC iterations, [1, 5000]."),
  };
  return table;
}

const Field* find_field(const std::string& name) {
  for (const Field& f : fields())
    if (name == f.name) return &f;
  return nullptr;
}

std::string field_names() {
  std::string names;
  for (const Field& f : fields()) names += (names.empty() ? "" : ", ") + std::string(f.name);
  return names;
}

// Parameters from keywords or a dict, as a parameter file reads them: a
// "frequency" first scales the frame-count parameters (for_frequency), the
// other keys then override; the result is validated. An unknown key is a
// TypeError among keywords, as Python's own, and a ValueError in a dict.
LoopDetectorParams params_from_items(const py::dict& items, bool keywords) {
  LoopDetectorParams params;
  for (const auto& [key, value] : items) {
    if (!py::isinstance<py::str>(key))
      throw py::type_error("loop detector parameter names are str, got " + type_name(key));
    if (!find_field(key.cast<std::string>())) {
      const std::string message = "unknown loop detector parameter \"" + key.cast<std::string>() +
                                  "\" (known: " + field_names() + ")";
      if (keywords) throw py::type_error(message);
      throw py::value_error(message);
    }
  }
  if (items.contains("frequency")) {
    LoopDetectorParams scaled;
    find_field("frequency")->set(scaled, items["frequency"]);
    params = LoopDetectorParams::for_frequency(scaled.frequency);
  }
  for (const auto& [key, value] : items) find_field(key.cast<std::string>())->set(params, value);
  params.validate();
  return params;
}

py::dict params_dict(const LoopDetectorParams& params) {
  py::dict out;
  for (const Field& f : fields()) out[f.name] = f.get(params);
  return out;
}

std::string params_repr(const LoopDetectorParams& params) {
  std::string text = "binbow.LoopDetectorParams(";
  bool first = true;
  for (const Field& f : fields()) {
    text += (first ? "" : ", ") + std::string(f.name) + "=" +
            py::repr(f.get(params)).cast<std::string>();
    first = false;
  }
  return text + ")";
}

// A parameter file's errors name the file; a dict's or a JSON text's are the
// caller's argument.
template <class Function>
LoopDetectorParams params_from_text(Function&& read) {
  try {
    return read();
  } catch (const FileError& e) {
    throw py::value_error(e.problem());
  }
}

void bind_params(py::module_& m) {
  auto cls = py::class_<LoopDetectorParams>(
      m, "LoopDetectorParams",
      "Every parameter of the loop detector (the paper's, at 1 Hz, by default).\n\n"
      "LoopDetectorParams(**fields): the defaults with the given fields; a frequency=\n"
      "first scales the frame-count parameters to it (as for_frequency and parameter\n"
      "files do), the other keywords then override. Values are checked as parameter\n"
      "files are: a wrong type is a TypeError, a value out of range a ValueError with\n"
      "the library's message, an unknown name a TypeError. Setting a property checks\n"
      "the new value the same way (frequency alone rescales nothing).");
  cls.def(py::init([](const py::kwargs& fields) { return params_from_items(fields, true); }),
          "The defaults with the given fields (see the class docstring).")
      .def_static("for_frequency", &LoopDetectorParams::for_frequency, py::arg("hz"),
                  "The defaults with the frame-count parameters scaled to hz images per second,\n"
                  "as DLoopDetector does (dislocal 20 f, max_db_results 50 f, ...).")
      .def_static(
          "from_file",
          [](const Path& path, const std::optional<LoopDetectorParams>& defaults) {
            py::gil_scoped_release release;
            return LoopDetectorParams::load(path.string(), defaults.value_or(LoopDetectorParams{}));
          },
          py::arg("path"), py::arg("defaults") = py::none(),
          "Read a JSON or YAML parameter file (the CLI's --params); keys it omits keep their\n"
          "value in defaults (the paper's when None). OSError naming the file and the key\n"
          "for anything invalid.")
      .def_static(
          "from_dict", [](const py::dict& d) { return params_from_items(d, false); }, py::arg("d"),
          "From a dict such as to_dict() returns; absent keys keep their defaults, a\n"
          "\"frequency\" key scales the frame counts first. Unknown keys and invalid values:\n"
          "ValueError; wrong types: TypeError.")
      .def("to_dict", &params_dict, "Every field by name: the keys of a parameter file.")
      .def_static(
          "from_json",
          [](const std::string& text) {
            return params_from_text([&] { return LoopDetectorParams::from_json(text); });
          },
          py::arg("text"), "From the JSON text to_json() writes (or a parameter file holds).")
      .def("to_json", &LoopDetectorParams::to_json,
           "Every field as a JSON object: a parameter file for the CLI's --params.")
      .def(
          "__eq__",
          [](const LoopDetectorParams& a, const LoopDetectorParams& b) {
            return a.to_json() == b.to_json();
          },
          py::is_operator(), "Every field equal.")
      .def("__repr__", &params_repr, "The constructor call with every field.")
      .def(
          "__copy__", [](const LoopDetectorParams& p) { return p; }, "A copy.")
      .def(
          "__deepcopy__", [](const LoopDetectorParams& p, const py::object&) { return p; },
          py::arg("memo"), "A copy.")
      .def(py::pickle([](const LoopDetectorParams& p) { return p.to_json(); },
                      [](const std::string& state) {
                        return params_from_text([&] {
                          return LoopDetectorParams::from_json(state,
                                                               "<pickled LoopDetectorParams>");
                        });
                      }));
  cls.attr("__hash__") = py::none();  // mutable, compared by value
  for (const Field& field : fields()) {
    cls.def_property(
        field.name, [&field](const LoopDetectorParams& p) { return field.get(p); },
        [&field](LoopDetectorParams& p, const py::handle& value) {
          LoopDetectorParams changed = p;
          field.set(changed, value);
          changed.validate();
          p = changed;
        },
        field.doc);
  }
}

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

// LoopDetector is used by one thread at a time; the Python object may be
// shared, so calls are serialised here rather than left to race.
class PythonLoopDetector {
 public:
  PythonLoopDetector(Vocabulary vocabulary, const LoopDetectorParams& params)
      : detector_(std::move(vocabulary), params) {}

  loop::SequenceFrame process(const py::handle& keypoints, const py::handle& descriptors) {
    const Descriptors d =
        to_descriptors(descriptors, "descriptors", detector_.database().vocabulary().code_size());
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
  void clear() {
    const std::lock_guard<std::mutex> lock(mutex_);
    detector_.clear();
  }
  // Both fixed at construction.
  const LoopDetectorParams& params() const { return detector_.params(); }
  const Vocabulary& vocabulary() const { return detector_.database().vocabulary(); }

 private:
  loop::LoopDetector detector_;
  mutable std::mutex mutex_;
};

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
                                              t.verification_ms, t.insertion_ms});
}

loop::SequenceFrame frame_from_state(const py::tuple& state) {
  constexpr int kLastStatus = static_cast<int>(loop::LoopStatus::kNoGeometricConsistency);
  if (state.size() != 19) throw py::value_error("invalid pickled binbow.LoopResult");
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
          "status", [](const loop::SequenceFrame& f) { return loop::to_string(f.result.status); },
          "Why the frame did or did not close a loop, as the CLI names it: \"loop-detected\",\n"
          "\"no-database-results\", \"low-normalisation-score\", \"low-scores\", \"no-islands\",\n"
          "\"no-temporal-consistency\", \"no-geometric-consistency\".")
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
          "exhaustive_fallback_used",
          [](const loop::SequenceFrame& f) { return f.result.exhaustive_fallback_used; },
          "Whether the geometric check retried with exhaustive matching.")
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
      .def("clear", &PythonLoopDetector::clear, "Forget every image; the next one is query 0.")
      .def_property_readonly("params", &PythonLoopDetector::params,
                             "The detector's parameters (a copy).")
      .def_property_readonly("vocabulary", &PythonLoopDetector::vocabulary,
                             "The detector's vocabulary.");
}

// --- Evaluation

// The detections of `results` (LoopResults, or a loops.csv path) as loops.csv rows.
std::vector<loop::Detection> detections_of(const py::handle& results) {
  if (py::isinstance<py::str>(results) || py::hasattr(results, "__fspath__")) {
    const std::string path =
        py::module_::import("os").attr("fsdecode")(results).cast<std::string>();
    py::gil_scoped_release release;
    return loop::read_detections_csv(path);
  }
  if (!py::isinstance<py::iterable>(results))
    throw py::type_error("results must be a list of LoopResult or a loops.csv path, got " +
                         type_name(results));
  std::vector<loop::Detection> detections;
  for (const py::handle item : results) {
    if (!py::isinstance<loop::SequenceFrame>(item))
      throw py::type_error("results must hold LoopResult objects, got " + type_name(item));
    const auto& frame = item.cast<const loop::SequenceFrame&>();
    const loop::LoopResult& r = frame.result;
    if (r.detection())
      detections.push_back(
          {r.query, r.match, frame.file, frame.match_file, r.normalised_score, r.inliers.size()});
  }
  return detections;
}

struct Evaluation {
  loop::PrecisionRecall measures;
  std::vector<std::tuple<std::size_t, std::size_t, bool>> verdicts;  // per detection
  std::map<std::size_t, bool> query_verdicts;  // per ground-truth query with a loop: found
};

Evaluation evaluate(const py::handle& results, const loop::GroundTruth& truth) {
  const std::vector<loop::Detection> detections = detections_of(results);
  py::gil_scoped_release release;
  Evaluation out;
  out.measures = loop::evaluate_detections(detections, truth);
  for (std::size_t q = 0; q < truth.frames(); ++q)
    if (truth.has_loop(q)) out.query_verdicts[q] = false;
  for (const loop::Detection& d : detections) {
    const bool correct = truth.is_loop(d.query, d.match);
    out.verdicts.emplace_back(d.query, d.match, correct);
    if (correct) out.query_verdicts[d.query] = true;
  }
  return out;
}

void bind_evaluation(py::module_& m) {
  py::class_<loop::GroundTruth>(
      m, "GroundTruth",
      "Which images of a sequence show the same place (symmetric; a query i has a loop\n"
      "when it shares a place with an earlier image). Stored sparsely.")
      .def(py::init<std::size_t, const std::vector<std::pair<std::size_t, std::size_t>>&>(),
           py::arg("frames"), py::arg("pairs"),
           "From 0-based (i, j) pairs of the same place among frames images.")
      .def_static(
          "load",
          [](const Path& path, std::optional<int> base, std::optional<std::size_t> frames) {
            loop::GroundTruthOptions options;
            if (base) {
              if (*base != 0 && *base != 1)
                throw py::value_error("base must be 0, 1 or None, got " + std::to_string(*base));
              options.pairs_index_base = *base;
            }
            options.frames = frames.value_or(0);
            py::gil_scoped_release release;
            return loop::GroundTruth::load(path.string(), options);
          },
          py::arg("path"), py::arg("base") = py::none(), py::arg("frames") = py::none(),
          "Load a ground truth as the CLI's evaluate --gt does: a square image (row = query,\n"
          "non-zero = same place), a MATLAB .mat matrix, or text pairs \"query match\".\n"
          "base: index base of text pairs, 0 or 1 (None: from a \"0-based\"/\"1-based\" comment,\n"
          "or 0 when an index 0 appears). frames: cut the ground truth to that many frames.")
      .def_property_readonly("frames", &loop::GroundTruth::frames, "Number of images.")
      .def("is_loop", &loop::GroundTruth::is_loop, py::arg("query"), py::arg("match"),
           "Whether the two images show the same place.")
      .def("has_loop", &loop::GroundTruth::has_loop, py::arg("query"),
           "Whether the image shares a place with an earlier one.")
      .def(
          "earlier_matches",
          [](const loop::GroundTruth& t, std::size_t query) {
            const Span<std::uint32_t> matches = t.earlier_matches(query);
            return std::vector<std::uint32_t>(matches.begin(), matches.end());
          },
          py::arg("query"), "Earlier images sharing a place with the query, increasing.")
      .def_property_readonly("queries_with_loops", &loop::GroundTruth::queries_with_loops,
                             "Number of images that share a place with an earlier one.")
      .def_property_readonly("pair_count", &loop::GroundTruth::pair_count,
                             "Number of (later, earlier) same-place pairs.")
      .def(
          "__repr__",
          [](const loop::GroundTruth& t) {
            return "<binbow.GroundTruth " + std::to_string(t.frames()) + " frames, " +
                   std::to_string(t.queries_with_loops()) + " queries with a loop>";
          },
          "Size as text.");

  py::class_<Evaluation>(m, "Evaluation",
                         "Precision and recall of detections (the paper's measures, as the\n"
                         "CLI's evaluate prints them), with the verdict on each detection and\n"
                         "each ground-truth query.")
      .def_property_readonly(
          "precision", [](const Evaluation& e) { return e.measures.precision; },
          "True positives / detections (1 without detections).")
      .def_property_readonly(
          "recall", [](const Evaluation& e) { return e.measures.recall; },
          "Queries found / queries with a loop.")
      .def_property_readonly(
          "detections", [](const Evaluation& e) { return e.measures.detections; },
          "Number of detections.")
      .def_property_readonly(
          "true_positives", [](const Evaluation& e) { return e.measures.true_positives; },
          "Detections the ground truth confirms.")
      .def_property_readonly(
          "false_positives", [](const Evaluation& e) { return e.measures.false_positives; },
          "Detections the ground truth denies.")
      .def_property_readonly(
          "queries_with_loops", [](const Evaluation& e) { return e.measures.queries_with_loops; },
          "Ground-truth queries that have a loop.")
      .def_property_readonly(
          "queries_found", [](const Evaluation& e) { return e.measures.queries_found; },
          "Distinct queries with a true positive.")
      .def_readonly("verdicts", &Evaluation::verdicts,
                    "(query, match, correct) of each detection, in the order of the results.")
      .def_readonly("query_verdicts", &Evaluation::query_verdicts,
                    "{query: found} for each ground-truth query with a loop, increasing.")
      .def(
          "__repr__",
          [](const Evaluation& e) {
            char text[160];
            std::snprintf(text, sizeof text,
                          "<binbow.Evaluation precision %.4g recall %.4g: %zu detections, %zu "
                          "true positives, %zu/%zu queries found>",
                          e.measures.precision, e.measures.recall, e.measures.detections,
                          e.measures.true_positives, e.measures.queries_found,
                          e.measures.queries_with_loops);
            return std::string(text);
          },
          "The measures as text.");

  m.def("evaluate", &evaluate, py::arg("results"), py::arg("ground_truth"),
        "Precision and recall of loop detections against a GroundTruth, as the CLI's evaluate:\n"
        "results is a list of LoopResult (detect_loops' or LoopDetector.process's, in order)\n"
        "or the path of a loops.csv. ValueError when a detection's index is outside the\n"
        "ground truth.");
}

// --- Sequences: detect_loops and write_report, faces of loop::SequenceDetector
// and loop::make_loop_report.

// As the CLI's --stride, --max-width and --video-fps accept.
vision::ImageSourceOptions source_options(long long stride, long long max_width, double video_fps) {
  if (stride < 1 || stride > 1000000)
    throw py::value_error("stride must be in [1, 1000000], got " + std::to_string(stride));
  if (max_width < 0 || max_width > 1000000)
    throw py::value_error("max_width must be in [0, 1000000], got " + std::to_string(max_width));
  if (!(video_fps >= 0 && video_fps <= 1000))
    throw py::value_error("video_fps must be in [0, 1000], got " + std::to_string(video_fps));
  vision::ImageSourceOptions source;
  source.stride = static_cast<std::size_t>(stride);
  source.max_width = static_cast<int>(max_width);
  source.video_fps = video_fps;
  return source;
}

// binbow.detect_loops (binbow/__init__.py) after its arguments are resolved:
// `descriptor` a name or a FeatureExtractor, `params` a LoopDetectorParams, a
// parameter file's path or None, `progress` None or a callable(done, total).
std::pair<std::vector<loop::SequenceFrame>, LoopDetectorParams> detect_loops(
    const std::vector<std::string>& inputs, Vocabulary vocabulary, const py::object& descriptor,
    const py::object& max_features, const py::object& params, long long stride, long long max_width,
    double video_fps, const py::object& progress) {
  loop::SequenceOptions options;
  options.source = source_options(stride, max_width, video_fps);
  if (const auto extractor = extractor_of(descriptor)) {
    if (!max_features.is_none())
      throw py::value_error(
          "max_features applies to a descriptor name; a FeatureExtractor has its own");
    options.extractor = extractor;
  } else if (py::isinstance<py::str>(descriptor)) {
    options.descriptor = descriptor.cast<std::string>();
    if (!max_features.is_none()) {
      if (!PyLong_Check(max_features.ptr()) || PyBool_Check(max_features.ptr()))
        throw py::type_error("max_features must be an int, got " + type_name(max_features));
      const auto count = max_features.cast<long long>();
      if (count < 1 || count > 1000000)
        throw py::value_error("max_features must be in [1, 1000000], got " + std::to_string(count));
      options.max_features = static_cast<int>(count);
    }
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
    sequence =
        given ? std::make_unique<loop::SequenceDetector>(inputs, std::move(vocabulary), options,
                                                         *given)
              : std::make_unique<loop::SequenceDetector>(inputs, std::move(vocabulary), options);
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
  return {std::move(frames), sequence->params()};
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

// The CLI's detect-loops report: make_loop_report's page with the facts the
// CLI shows (inputs, frequency, vocabulary, descriptor) where the run knew them.
std::string write_report(const Path& folder, const py::handle& results,
                         const loop::GroundTruth* truth,
                         const std::optional<LoopDetectorParams>& params, const std::string& inputs,
                         const std::string& vocabulary, const std::string& descriptor) {
  const std::vector<loop::SequenceFrame> frames = frames_of(results);
  py::gil_scoped_release release;
  loop::LoopReport report =
      loop::make_loop_report(frames, params.value_or(LoopDetectorParams{}), truth);
  if (params) {
    char hertz[32];
    std::snprintf(hertz, sizeof hertz, "%g Hz", params->frequency);
    report.facts.emplace_back("frequency", hertz);
  } else {
    report.params_json.clear();  // not known: not shown as the defaults
  }
  if (!inputs.empty()) report.facts.insert(report.facts.begin(), {"inputs", inputs});
  if (!vocabulary.empty()) report.facts.emplace_back("vocabulary", vocabulary);
  if (!descriptor.empty()) report.facts.emplace_back("descriptor", descriptor);
  return loop::write_loop_report(folder.string(), report);
}

void bind_sequences(py::module_& m) {
  m.def("_detect_loops", &detect_loops, py::arg("inputs"), py::arg("vocabulary"),
        py::arg("descriptor"), py::arg("max_features"), py::arg("params"), py::arg("stride"),
        py::arg("max_width"), py::arg("video_fps"), py::arg("progress"),
        "binbow.detect_loops once its arguments are resolved (use that): the frames and\n"
        "the parameters used.");
  m.def("_write_report", &write_report, py::arg("folder"), py::arg("results"),
        py::arg("ground_truth"), py::arg("params"), py::arg("inputs"), py::arg("vocabulary"),
        py::arg("descriptor"), "binbow.write_report with the run's facts resolved (use that).");
}

}  // namespace

void bind_loop(py::module_& m) {
  bind_params(m);
  bind_detection(m);
  bind_evaluation(m);
  bind_sequences(m);
}

}  // namespace binbow::python
