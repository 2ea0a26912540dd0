// binbow.LoopDetectorParams: every field of loop::LoopDetectorParams as a
// property, checked as parameter files are.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <climits>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/loop_detector.h"
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
      bool_field("skip_featureless_frames", &P::skip_featureless_frames,
                 "An image without features neither normalises the next scores nor breaks\n"
                 "the temporal chain (binbow's addition)."),
      int_field("dislocal", &P::dislocal,
                "Candidates of image t are images j < t - dislocal (20 f), [0, 1e6]."),
      int_field("max_db_results", &P::max_db_results,
                "Candidates taken from each database query (50 f), [1, 1e6]."),
      bool_field("fast_queries", &P::fast_queries,
                 "Query the database in fast mode (exact scores of the candidates that the\n"
                 "query's rarest words find)."),
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
      bool_field("mutual_matching", &P::mutual_matching,
                 "Keep only correspondences that are each other's nearest neighbour."),
      Field{"fundamental_estimator",
            "The robust estimator of the fundamental matrix: \"usac-magsac\" (binbow's\n"
            "default, MAGSAC++), \"usac-accurate\" or \"ransac\" (the paper's).",
            [](const P& p) { return py::str(vision::to_string(p.fundamental_estimator)); },
            [](P& p, const py::handle& value) {
              if (!py::isinstance<py::str>(value))
                throw py::type_error(
                    "loop detector parameter fundamental_estimator must be a str, got " +
                    type_name(value));
              p.fundamental_estimator =
                  vision::parse_fundamental_estimator(value.cast<std::string>());
            }},
      int_field("min_inliers", &P::min_inliers,
                "Minimum RANSAC inliers of the fundamental matrix, [8, 10000]."),
      real_field("max_reprojection_error", &P::max_reprojection_error,
                 "RANSAC threshold in pixels, [0.1, 100]."),
      real_field("ransac_confidence", &P::ransac_confidence, "RANSAC confidence, (0, 1)."),
      int_field("max_ransac_iterations", &P::max_ransac_iterations,
                "RANSAC iterations, [1, 5000]."),
      real_field("min_inlier_ratio", &P::min_inlier_ratio,
                 "Minimum inliers / correspondences of the fundamental matrix, [0, 1]."),
      real_field("min_inlier_spread", &P::min_inlier_spread,
                 "Minimum share of the image the inliers must cover, [0, 1]."),
      bool_field("reject_degenerate_fits", &P::reject_degenerate_fits,
                 "A fit whose inliers do not determine its geometry (points near a line, on\n"
                 "one small patch, too few distinct points) accepts no loop."),
      int_field("min_uncorroborated_inliers", &P::min_uncorroborated_inliers,
                "Fewer inliers need corroboration (a loop just before, or a neighbour of the "
                "match), [0, 10000] (0: off)."),
      real_field("min_uncorroborated_view_agreement", &P::min_uncorroborated_view_agreement,
                 "A fit with min_uncorroborated_inliers inliers or more that explains less than\n"
                 "this share of both views (view agreement) needs corroboration, [0, 1] (0: off)."),
      bool_field("strong_fits_skip_temporal_check", &P::strong_fits_skip_temporal_check,
                 "A fit with min_uncorroborated_inliers inliers or more is a loop without\n"
                 "temporal consistency."),
      int_field("corroboration_distance", &P::corroboration_distance,
                "Frames from the loop before them that weak loops accept, [1, 1e6]."),
      int_field("corroboration_horizon", &P::corroboration_horizon,
                "Queries after the loop before them that weak loops at the revisit's pace "
                "accept, [1, 1e6]."),
      real_field("corroboration_pace_tolerance", &P::corroboration_pace_tolerance,
                 "How far a weak loop may stray from the revisit's pace, as a fraction of the "
                 "queries since the loop before it, [0, 1]."),
      bool_field("localise_in_island", &P::localise_in_island,
                 "An accepted loop moves to the entry of its island that is also accepted with\n"
                 "more inliers and more of the view reappearing where the fit puts it."),
      int_field("max_localisation_checks", &P::max_localisation_checks,
                "Other candidates of the island localisation checks, best first, [1, 50]."),
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

}  // namespace

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
        [&field](LoopDetectorParams& p, const py::object& value) {
          LoopDetectorParams changed = p;
          field.set(changed, value);
          changed.validate();
          p = changed;
        },
        field.doc);
  }
}

}  // namespace binbow::python
