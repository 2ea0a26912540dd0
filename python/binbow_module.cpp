// Python bindings: descriptors are numpy uint8 arrays of shape (n, code_size),
// BoW vectors are BowVector objects with numpy views; the GIL is released
// around every call that does real work, so threads can run in parallel.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <tuple>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/vocabulary.h"

namespace py = pybind11;
using namespace binbow;

namespace {

using Bytes = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>;

DescriptorView as_view(const Bytes& array) {
  if (array.ndim() != 2)
    throw InvalidArgument("descriptors must be a 2-D uint8 array of shape (n, code_size), got " +
                          std::to_string(array.ndim()) + " dimensions");
  return {array.data(), static_cast<std::size_t>(array.shape(0)),
          static_cast<std::size_t>(array.shape(1))};
}

py::array_t<WordId> words_of(const BowVector& bow) {
  py::array_t<WordId> out(static_cast<py::ssize_t>(bow.size()));
  for (std::size_t i = 0; i < bow.size(); ++i) out.mutable_at(i) = bow[i].word;
  return out;
}

py::array_t<float> values_of(const BowVector& bow) {
  py::array_t<float> out(static_cast<py::ssize_t>(bow.size()));
  for (std::size_t i = 0; i < bow.size(); ++i) out.mutable_at(i) = bow[i].value;
  return out;
}

BowVector bow_from_arrays(const py::array_t<WordId>& words, const py::array_t<float>& values) {
  if (words.ndim() != 1 || values.ndim() != 1 || words.size() != values.size())
    throw InvalidArgument("words and values must be 1-D arrays of the same length");
  std::vector<BowEntry> entries(static_cast<std::size_t>(words.size()));
  for (std::size_t i = 0; i < entries.size(); ++i) entries[i] = {words.at(i), values.at(i)};
  return BowVector(std::move(entries));
}

py::dict feature_vector_dict(const FeatureVector& fv) {
  py::dict out;
  for (std::size_t i = 0; i < fv.size(); ++i) {
    const auto f = fv.features(i);
    out[py::int_(fv.node(i))] =
        py::array_t<std::uint32_t>(static_cast<py::ssize_t>(f.size()), f.data());
  }
  return out;
}

std::vector<std::tuple<EntryId, double, std::uint32_t>> results_list(
    const std::vector<QueryResult>& results) {
  std::vector<std::tuple<EntryId, double, std::uint32_t>> out;
  out.reserve(results.size());
  for (const QueryResult& r : results) out.emplace_back(r.entry, r.score, r.shared_words);
  return out;
}

}  // namespace

PYBIND11_MODULE(binbow, m) {
  m.doc() = "Bags of binary words for fast place recognition (Galvez-Lopez & Tardos 2012)";

  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InvalidArgument& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const FileError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    } catch (const Error& e) {
      error(e.what());
    }
  });

  m.def(
      "hamming",
      [](const Bytes& a, const Bytes& b) {
        if (a.ndim() != 1 || b.ndim() != 1 || a.size() != b.size())
          throw InvalidArgument("hamming takes two 1-D uint8 arrays of the same length");
        return hamming_distance(a.data(), b.data(), static_cast<std::size_t>(a.size()));
      },
      py::arg("a"), py::arg("b"), "Number of differing bits between two descriptors.");

  py::class_<BowVector>(m, "BowVector", "Sparse bag-of-words vector, sorted by word id.")
      .def(py::init(&bow_from_arrays), py::arg("words"), py::arg("values"))
      .def_property_readonly("words", &words_of, "word ids (uint32)")
      .def_property_readonly("values", &values_of, "normalised weights (float32)")
      .def("__len__", &BowVector::size)
      .def("__eq__", [](const BowVector& a, const BowVector& b) { return a == b; })
      .def("__repr__", [](const BowVector& b) {
        return "<binbow.BowVector with " + std::to_string(b.size()) + " words>";
      });

  py::class_<Vocabulary>(m, "Vocabulary", "A vocabulary tree of binary words.")
      .def_static(
          "load", [](const std::string& path) { return load_vocabulary(path); }, py::arg("path"),
          py::call_guard<py::gil_scoped_release>(),
          "Load any supported format (.bbw, DBoW2 YAML, ORBvoc.txt, DBoW3, fbow).")
      .def(
          "save", [](const Vocabulary& v, const std::string& path) { save_vocabulary(v, path); },
          py::arg("path"), py::call_guard<py::gil_scoped_release>(),
          "Save; the extension chooses the format (.bbw, .txt, .yml.gz, .dbow3, .fbow).")
      .def_static(
          "build",
          [](const std::vector<Bytes>& images, std::uint32_t branching, std::uint32_t levels,
             const std::string& weighting, const std::string& scoring, std::uint64_t seed,
             unsigned threads, const std::string& descriptor) {
            std::vector<DescriptorView> views;
            for (const Bytes& image : images) views.push_back(as_view(image));
            BuildOptions options;
            options.branching = branching;
            options.levels = levels;
            options.weighting = parse_weighting(weighting);
            options.scoring = parse_scoring(scoring);
            options.seed = seed;
            options.threads = threads;
            options.descriptor = descriptor;
            py::gil_scoped_release release;
            return Vocabulary::build(views, options);
          },
          py::arg("images"), py::arg("branching") = 10, py::arg("levels") = 6,
          py::arg("weighting") = "tf-idf", py::arg("scoring") = "l1", py::arg("seed") = 0,
          py::arg("threads") = 0, py::arg("descriptor") = "",
          "Hierarchical k-medians over a list of (n_i, code_size) uint8 arrays, one per image;\n"
          "descriptor names the extractor (\"orb\", \"brief\", ...) to record in the vocabulary.")
      .def(
          "transform",
          [](const Vocabulary& v, const Bytes& descriptors) {
            const DescriptorView view = as_view(descriptors);
            BowVector bow;
            py::gil_scoped_release release;
            v.transform(view, bow);
            return bow;
          },
          py::arg("descriptors"), "Descriptors → BowVector.")
      .def(
          "transform_with_features",
          [](const Vocabulary& v, const Bytes& descriptors, unsigned levels_up) {
            const DescriptorView view = as_view(descriptors);
            BowVector bow;
            FeatureVector fv;
            {
              py::gil_scoped_release release;
              v.transform(view, bow, fv, levels_up);
            }
            return py::make_tuple(bow, feature_vector_dict(fv));
          },
          py::arg("descriptors"), py::arg("levels_up") = 4,
          "Descriptors → (BowVector, {node id: feature indices}).")
      .def(
          "quantize",
          [](const Vocabulary& v, const Bytes& descriptors) {
            const DescriptorView view = as_view(descriptors);
            py::array_t<WordId> words(static_cast<py::ssize_t>(view.rows));
            WordId* out = words.mutable_data();
            py::gil_scoped_release release;
            v.quantize(view, out);
            return words;
          },
          py::arg("descriptors"), "Word id of every descriptor.")
      .def("score", &Vocabulary::score, py::arg("a"), py::arg("b"))
      .def_property_readonly("word_count", &Vocabulary::word_count)
      .def_property_readonly("node_count", &Vocabulary::node_count)
      .def_property_readonly("branching", &Vocabulary::branching)
      .def_property_readonly("levels", &Vocabulary::levels)
      .def_property_readonly("code_size", &Vocabulary::code_size)
      .def_property_readonly(
          "descriptor", &Vocabulary::descriptor,
          "Extractor that trained it (\"orb\", \"brief\", ...), \"\" if unknown.")
      .def_property_readonly("weighting",
                             [](const Vocabulary& v) { return to_string(v.weighting()); })
      .def_property_readonly("scoring", [](const Vocabulary& v) { return to_string(v.scoring()); })
      .def("__repr__",
           [](const Vocabulary& v) { return "<binbow.Vocabulary " + v.description() + ">"; });

  py::class_<Database>(m, "Database", "Inverted + direct index of images over a vocabulary.")
      .def(py::init([](Vocabulary vocabulary, bool direct_index, unsigned levels_up) {
             DatabaseOptions options;
             options.direct_index = direct_index;
             options.direct_index_levels_up = levels_up;
             return Database(std::move(vocabulary), options);
           }),
           py::arg("vocabulary"), py::arg("direct_index") = true, py::arg("levels_up") = 4)
      .def(
          "add",
          [](Database& db, const Bytes& descriptors) {
            const DescriptorView view = as_view(descriptors);
            py::gil_scoped_release release;
            return db.add(view);
          },
          py::arg("descriptors"), "Transform and add an image; returns its entry id.")
      .def(
          "add_bow", [](Database& db, const BowVector& bow) { return db.add(bow); }, py::arg("bow"),
          py::call_guard<py::gil_scoped_release>())
      .def(
          "query",
          [](const Database& db, const BowVector& bow, std::size_t max_results,
             long long max_entry) {
            std::vector<QueryResult> results;
            {
              py::gil_scoped_release release;
              results = db.query(bow, max_results,
                                 max_entry < 0 ? kAllEntries : static_cast<EntryId>(max_entry));
            }
            return results_list(results);
          },
          py::arg("bow"), py::arg("max_results") = 10, py::arg("max_entry_id") = -1,
          "Best matches as a list of (entry, score, shared_words), best first.")
      .def("remove", &Database::remove, py::arg("entry"))
      .def("__contains__", &Database::contains)
      .def("__len__", &Database::size)
      .def("clear", &Database::clear)
      .def("feature_vector",
           [](const Database& db, EntryId entry) {
             return feature_vector_dict(db.feature_vector(entry));
           })
      .def_property_readonly("vocabulary", &Database::vocabulary)
      .def("save", &Database::save, py::arg("path"), py::arg("include_vocabulary") = true,
           py::call_guard<py::gil_scoped_release>())
      .def_static(
          "load", [](const std::string& path) { return Database::load(path); }, py::arg("path"),
          py::call_guard<py::gil_scoped_release>());
}
