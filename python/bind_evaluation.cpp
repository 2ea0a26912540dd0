// binbow.GroundTruth and binbow.evaluate: the CLI's evaluate over LoopResults
// or a loops.csv.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "binbow/loop/evaluation.h"
#include "binbow/loop/sequence.h"
#include "binding.h"

namespace binbow::python {
namespace {

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

Evaluation evaluate(const py::object& results, const loop::GroundTruth& truth) {
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

}  // namespace

void bind_evaluation(py::module_& m) {
  py::class_<loop::GroundTruth>(
      m, "GroundTruth",
      "Which images of a sequence show the same place (symmetric; a query i has a loop\n"
      "when it shares a place with an earlier image). Stored sparsely.")
      .def(py::init([](const py::object& frames, const py::iterable& pairs) {
             std::vector<std::pair<std::size_t, std::size_t>> indices;
             for (const py::handle pair : pairs) {
               const std::string name = "pairs[" + std::to_string(indices.size()) + "]";
               if (!py::isinstance<py::sequence>(pair) || py::len(pair) != 2)
                 throw py::type_error(name + " must be a pair of ints (i, j), got " +
                                      type_name(pair));
               const auto both = py::reinterpret_borrow<py::sequence>(pair);
               indices.emplace_back(int_argument<std::size_t>(both[0], name + "[0]"),
                                    int_argument<std::size_t>(both[1], name + "[1]"));
             }
             return loop::GroundTruth(int_argument<std::size_t>(frames, "frames"), indices);
           }),
           py::arg("frames"), py::arg("pairs"),
           "From 0-based (i, j) pairs of the same place among frames images.")
      .def_static(
          "load",
          [](const Path& path, const py::object& base, const py::object& frames) {
            loop::GroundTruthOptions options;
            if (!base.is_none()) {
              const py::int_ number = int_of(base, "base");
              if (!int_in_range(number, py::int_(0), py::int_(1)))
                throw py::value_error("base must be 0, 1 or None, got " + int_text(number));
              options.pairs_index_base = number.cast<int>();
            }
            if (!frames.is_none()) options.frames = int_argument<std::size_t>(frames, "frames");
            py::gil_scoped_release release;
            return loop::GroundTruth::load(path.string(), options);
          },
          py::arg("path"), py::arg("base") = py::none(), py::arg("frames") = py::none(),
          "Load a ground truth as the CLI's evaluate --gt does: a square image (row = query,\n"
          "non-zero = same place), a MATLAB .mat matrix, or text pairs \"query match\".\n"
          "base: index base of text pairs, 0 or 1 (None: from a \"0-based\"/\"1-based\" comment,\n"
          "or 0 when an index 0 appears). frames: cut the ground truth to that many frames.")
      .def_property_readonly("frames", &loop::GroundTruth::frames, "Number of images.")
      .def(
          "is_loop",
          [](const loop::GroundTruth& t, const py::object& query, const py::object& match) {
            return t.is_loop(int_argument<std::size_t>(query, "query"),
                             int_argument<std::size_t>(match, "match"));
          },
          py::arg("query"), py::arg("match"), "Whether the two images show the same place.")
      .def(
          "has_loop",
          [](const loop::GroundTruth& t, const py::object& query) {
            return t.has_loop(int_argument<std::size_t>(query, "query"));
          },
          py::arg("query"), "Whether the image shares a place with an earlier one.")
      .def(
          "earlier_matches",
          [](const loop::GroundTruth& t, const py::object& query) {
            return t.earlier_matches(int_argument<std::size_t>(query, "query"));
          },
          py::arg("query"), "Earlier images sharing a place with the query, increasing.")
      .def(
          "earlier_match_ranges",
          [](const loop::GroundTruth& t, const py::object& query) {
            std::vector<std::pair<std::uint32_t, std::uint32_t>> ranges;
            for (const loop::FrameRange& r :
                 t.earlier_match_ranges(int_argument<std::size_t>(query, "query")))
              ranges.emplace_back(r.first, r.end);
            return ranges;
          },
          py::arg("query"),
          "The same images as (first, end) ranges of consecutive frames, end excluded: "
          "compact when a query matches many.")
      .def_property_readonly("range_count", &loop::GroundTruth::range_count,
                             "Number of ranges stored: what the ground truth's memory follows.")
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

}  // namespace binbow::python
