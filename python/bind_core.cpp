// The core room: descriptors, BowVector, Vocabulary, Database (no OpenCV).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "binding.h"
#include "database/database_impl.h"

namespace binbow::python {
namespace {

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

// Word ids must be integers in the uint32 range and values real numbers: a
// negative id must not wrap around to a large one.
BowVector bow_from_arrays(const py::array& words, const py::array& values) {
  const char words_kind = words.dtype().kind();
  if (words_kind != 'i' && words_kind != 'u')
    throw py::type_error("words must be an integer array, got dtype " +
                         py::str(words.dtype()).cast<std::string>());
  const char values_kind = values.dtype().kind();
  if (values_kind != 'f' && values_kind != 'i' && values_kind != 'u')
    throw py::type_error("values must be a real-valued array, got dtype " +
                         py::str(values.dtype()).cast<std::string>());
  if (words.ndim() != 1 || values.ndim() != 1 || words.size() != values.size())
    throw py::value_error("words and values must be 1-D arrays of the same length, got shapes " +
                          shape_of(words) + " and " + shape_of(values));
  const auto ids = py::array_t<std::int64_t, py::array::forcecast>::ensure(words);
  const auto weights = py::array_t<float, py::array::forcecast>::ensure(values);
  if (!ids || !weights) throw py::error_already_set();
  std::vector<BowEntry> entries(static_cast<std::size_t>(words.size()));
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const std::int64_t id = ids.at(static_cast<py::ssize_t>(i));
    if (words_kind == 'u' ? static_cast<std::uint64_t>(id) > std::numeric_limits<WordId>::max()
                          : (id < 0 || id > std::int64_t{std::numeric_limits<WordId>::max()}))
      throw py::value_error("words[" + std::to_string(i) + "] is not a word id (0 to 2**32 - 1)");
    entries[i] = {static_cast<WordId>(id), weights.at(static_cast<py::ssize_t>(i))};
  }
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

Vocabulary vocabulary_from_bytes(const py::bytes& state) {
  const auto [data, size] = bytes_of(state);
  py::gil_scoped_release release;
  return Vocabulary::deserialize(data, size, "<pickled binbow.Vocabulary>");
}

py::bytes vocabulary_bytes(const Vocabulary& vocabulary) {
  std::vector<std::uint8_t> bytes;
  {
    py::gil_scoped_release release;
    bytes = vocabulary.serialize();
  }
  return to_bytes(bytes);
}

// Vocabulary::build's progress callback runs on the calling thread, which has
// released the GIL; an exception it raises (KeyboardInterrupt, ...) stops the
// build and reaches the caller.
std::function<void(const BuildProgress&)> progress_callback(const py::object& progress) {
  if (progress.is_none()) return {};
  if (!PyCallable_Check(progress.ptr()))
    throw py::type_error("progress must be callable, got " + type_name(progress));
  return [progress](const BuildProgress& state) {
    py::gil_scoped_acquire acquire;
    progress(state);
  };
}

Vocabulary build_vocabulary(const py::iterable& images, const py::object& branching,
                            const py::object& levels, const std::string& weighting,
                            const std::string& scoring, const py::object& seed,
                            const py::object& threads, const std::string& descriptor,
                            double stop_word_fraction, const py::object& max_iterations,
                            const py::object& progress) {
  if (py::isinstance<py::array>(images))
    throw py::type_error(
        "images must be a list of descriptor arrays, one per training image; got one array "
        "(wrap it in a list if it is one image)");
  std::vector<Descriptors> arrays;
  std::size_t index = 0;
  for (const py::handle image : images)
    arrays.push_back(to_descriptors(image, "images[" + std::to_string(index++) + "]", 0));
  std::vector<DescriptorView> views;
  views.reserve(arrays.size());
  for (const Descriptors& d : arrays) views.push_back(d.view);
  BuildOptions options;
  options.branching = int_argument<std::uint32_t>(branching, "branching");
  options.levels = int_argument<std::uint32_t>(levels, "levels");
  options.weighting = parse_weighting(weighting);
  options.scoring = parse_scoring(scoring);
  options.seed = int_argument<std::uint64_t>(seed, "seed");
  options.threads = int_argument<unsigned>(threads, "threads");
  options.descriptor = descriptor;
  options.stop_word_fraction = stop_word_fraction;
  options.max_iterations = int_argument<unsigned>(max_iterations, "max_iterations");
  options.progress = progress_callback(progress);
  py::gil_scoped_release release;
  return Vocabulary::build(views, options);
}

// None or a str; taken here rather than by pybind11, whose error would print
// every argument, the descriptor array included.
std::string label_argument(const py::handle& label) {
  if (label.is_none()) return {};
  if (!py::isinstance<py::str>(label))
    throw py::type_error("label must be a str or None, got " + type_name(label));
  return label.cast<std::string>();
}

EntryId add_descriptors(Database& db, const py::object& descriptors, const py::object& label) {
  const Descriptors d = to_descriptors(descriptors, "descriptors", db.vocabulary().code_size());
  std::string text = label_argument(label);
  py::gil_scoped_release release;
  return db.add(d.view, std::move(text));
}

// A non-negative int (not bool) of up to 64 bits (int_argument).
std::uint64_t count_argument(const py::handle& value, const std::string& name) {
  return int_argument<std::uint64_t>(value, name);
}

// The id of an entry given to Database.<method>, if it can be one: an int
// (TypeError otherwise) that an EntryId holds.
std::optional<EntryId> entry_id(const py::handle& value, const char* method) {
  const py::int_ number = int_of(value, std::string("Database.") + method + ": entry");
  if (!int_in_range(number, py::int_(0), py::int_(std::numeric_limits<EntryId>::max())))
    return std::nullopt;
  return number.cast<EntryId>();
}

// entry_id, or for an int no entry id can be (negative, or past 2^32 - 1)
// the library's ValueError for an entry that does not exist, as
// ShardedDatabase reports it.
EntryId existing_entry_id(const Database& db, const py::handle& value, const char* method) {
  if (const std::optional<EntryId> id = entry_id(value, method)) return *id;
  throw py::value_error(std::string("Database::") + method + ": entry " +
                        int_text(py::reinterpret_borrow<py::int_>(value)) +
                        " does not exist (the database has ids below " +
                        std::to_string(db.next_entry_id()) + ")");
}

// The BowVector of `image`: itself, or the transform of its descriptors.
BowVector bow_of(const Database& db, const py::handle& image) {
  if (py::isinstance<BowVector>(image)) return image.cast<BowVector>();
  if (!image.is_none() && !py::isinstance<py::array>(image))
    throw py::type_error("image must be a BowVector or descriptors (a numpy uint8 array), got " +
                         type_name(image));
  const Descriptors d = to_descriptors(image, "descriptors", db.vocabulary().code_size());
  BowVector bow;
  py::gil_scoped_release release;
  db.vocabulary().transform(d.view, bow);
  return bow;
}

// Database.query's fast-mode keywords (None: QueryOptions' default) as
// QueryOptions, checked as Database::query checks them, so that
// ShardedDatabase refuses the same values with the same errors before any
// shard is called.
QueryOptions query_options(bool fast, const py::object& fast_candidates,
                           const py::object& fast_candidate_share,
                           const py::object& fast_min_postings) {
  QueryOptions options;
  if (fast) options.mode = QueryMode::kFast;
  if (!fast && (!fast_candidates.is_none() || !fast_candidate_share.is_none() ||
                !fast_min_postings.is_none()))
    throw InvalidArgument(
        "fast_candidates, fast_candidate_share and fast_min_postings apply to fast=True only");
  if (!fast_candidate_share.is_none())
    options.fast_candidate_share = float_option(fast_candidate_share, "fast_candidate_share");
  if (!fast_candidates.is_none())
    options.fast_candidates =
        static_cast<std::size_t>(count_argument(fast_candidates, "fast_candidates"));
  if (!fast_min_postings.is_none())
    options.fast_min_postings = count_argument(fast_min_postings, "fast_min_postings");
  options.check();
  return options;
}

std::vector<std::tuple<EntryId, double, std::uint32_t>> query_database(
    const Database& db, const py::object& image, const py::object& max_results,
    const py::object& max_entry_id, bool fast, const py::object& fast_candidates,
    const py::object& fast_candidate_share, const py::object& fast_min_postings) {
  const std::uint64_t count = count_argument(max_results, "max_results");
  const QueryOptions options =
      query_options(fast, fast_candidates, fast_candidate_share, fast_min_postings);
  EntryId last = kAllEntries;
  if (!max_entry_id.is_none()) {
    const std::uint64_t id = count_argument(max_entry_id, "max_entry_id");
    last = static_cast<EntryId>(std::min<std::uint64_t>(id, kAllEntries));
  }
  const BowVector bow = bow_of(db, image);
  std::vector<QueryResult> results;
  {
    py::gil_scoped_release release;
    results = db.query(bow, static_cast<std::size_t>(count), last, options);
  }
  return results_list(results);
}

py::bytes database_bytes(const Database& db, bool include_vocabulary) {
  std::vector<std::uint8_t> bytes;
  {
    py::gil_scoped_release release;
    bytes = db.serialize(include_vocabulary);
  }
  return to_bytes(bytes);
}

// Copies share the (immutable) vocabulary; only the index is duplicated.
Database copy_database(const Database& db) {
  std::vector<std::uint8_t> bytes;
  py::gil_scoped_release release;
  bytes = db.serialize(false);
  return Database::deserialize(bytes.data(), bytes.size(), "<copied binbow.Database>",
                               db.vocabulary());
}

// Database.load's verification=: "background" (DatabaseLoadOptions' default)
// or "before-return", spelled as the module's other names of a C++ enum.
DatabaseLoadOptions load_options(const std::string& verification) {
  DatabaseLoadOptions options;
  if (verification == "before-return")
    options.verification = Verification::kBeforeReturn;
  else if (verification != "background")
    throw InvalidArgument("unknown verification '" + verification +
                          "' (expected one of background, before-return)");
  return options;
}

std::string database_repr(const Database& db) {
  return "<binbow.Database with " + std::to_string(db.size()) + " entries, vocabulary " +
         db.vocabulary().description() + ">";
}

}  // namespace

void bind_core(py::module_& m) {
  // Database's own argument checks, for binbow.distributed.ShardedDatabase to
  // refuse the same mistakes with the same errors before any shard is called.
  m.def(
      "_checked_descriptors",
      [](const py::object& descriptors, const std::string& what, std::size_t code_size) {
        if (descriptors.is_none()) return py::object(py::none());
        return py::object(to_descriptors(descriptors, what, code_size).array);
      },
      py::arg("descriptors"), py::arg("what"), py::arg("code_size"));
  m.def(
      "_check_bow",
      [](const BowVector& bow, const Vocabulary& vocabulary) {
        detail::check_bow_words(bow, vocabulary, "Database::add");
        detail::check_bow_values(bow, "Database::add");
      },
      py::arg("bow"), py::arg("vocabulary"));
  m.def(
      "_check_query_options",
      [](bool fast, const py::object& fast_candidates, const py::object& fast_candidate_share,
         const py::object& fast_min_postings) {
        query_options(fast, fast_candidates, fast_candidate_share, fast_min_postings);
      },
      py::arg("fast"), py::arg("fast_candidates"), py::arg("fast_candidate_share"),
      py::arg("fast_min_postings"));
  m.def("_count_argument", &count_argument, py::arg("value"), py::arg("name"));
  m.def("_label_argument", &label_argument, py::arg("label"));

  m.def(
      "hamming",
      [](const py::object& a, const py::object& b) {
        const py::array x = checked_uint8_array(a, "a");
        const py::array y = checked_uint8_array(b, "b");
        if (x.ndim() != 1 || y.ndim() != 1 || x.size() != y.size())
          throw py::value_error(
              "hamming takes two 1-D descriptors of the same length, got shapes " + shape_of(x) +
              " and " + shape_of(y));
        const auto u = contiguous_uint8(x, "a");
        const auto v = contiguous_uint8(y, "b");
        return hamming_distance(u.data(), v.data(), static_cast<std::size_t>(u.size()));
      },
      py::arg("a"), py::arg("b"),
      "Number of differing bits between two descriptors (1-D uint8 arrays of equal length).");

  py::class_<BuildProgress>(m, "BuildProgress",
                            "Progress of Vocabulary.build, passed to its progress callable.")
      .def_readonly("clustered_descriptors", &BuildProgress::clustered_descriptors,
                    "Descriptors that reached a leaf so far.")
      .def_readonly("total_descriptors", &BuildProgress::total_descriptors,
                    "Descriptors being clustered.")
      .def_readonly("nodes", &BuildProgress::nodes, "Tree nodes created so far.")
      .def(
          "__repr__",
          [](const BuildProgress& p) {
            return "<binbow.BuildProgress " + std::to_string(p.clustered_descriptors) + "/" +
                   std::to_string(p.total_descriptors) + " descriptors, " +
                   std::to_string(p.nodes) + " nodes>";
          },
          "Counts as text.");

  py::class_<BowVector>(m, "BowVector",
                        "Sparse bag-of-words vector: words sorted by id, with their weights.")
      .def(py::init(&bow_from_arrays), py::arg("words"), py::arg("values"),
           "From word ids (integers, strictly increasing) and their values.")
      .def_property_readonly("words", &words_of, "Word ids, increasing (uint32 array).")
      .def_property_readonly("values", &values_of, "Normalised weights (float32 array).")
      .def("__len__", &BowVector::size, "Number of words present.")
      .def(
          "__eq__", [](const BowVector& a, const BowVector& b) { return a == b; },
          py::is_operator(), "Same words with the same values.")
      .def(
          "__repr__",
          [](const BowVector& b) {
            return "<binbow.BowVector with " + std::to_string(b.size()) + " words>";
          },
          "Size as text.")
      .def(py::pickle([](const BowVector& b) { return py::make_tuple(words_of(b), values_of(b)); },
                      [](const py::tuple& state) {
                        if (state.size() != 2)
                          throw py::value_error("invalid pickled binbow.BowVector");
                        return bow_from_arrays(state[0].cast<py::array>(),
                                               state[1].cast<py::array>());
                      }));

  py::class_<Vocabulary>(m, "Vocabulary",
                         "A vocabulary tree of binary words. Immutable: copies share the tree.")
      .def_static(
          "load",
          [](const Path& path, const std::string& format, const std::string& descriptor) {
            try {
              return load_vocabulary(path.string(), parse_vocabulary_format(format), descriptor);
            } catch (const FileError& e) {
              if (e.problem().rfind(kUnknownVocabularyFormat, 0) != 0) throw;
              throw FileError(e.path(), e.problem() + " with Vocabulary.load(path, format=...)");
            }
          },
          py::arg("path"), py::arg("format") = "auto", py::kw_only(), py::arg("descriptor") = "",
          py::call_guard<py::gil_scoped_release>(),
          "Load any supported format (.bbw, DBoW2 YAML, ORBvoc.txt, ORB-SLAM .bin, DBoW3, fbow,\n"
          "VINS brief_k10L6.bin). format: \"auto\" (detect from the content, then the\n"
          "extension) or one of \"bbw\", \"dbow2\", \"orbslam-text\", \"orbslam-binary\",\n"
          "\"dbow3\", \"fbow\", \"vins\". descriptor: the extractor the vocabulary was trained\n"
          "on (\"orb\", \"brief\", ...) for files that do not record it (all but .bbw); without\n"
          "it a VINS file is brief, and another file of 256-bit descriptors is taken for orb\n"
          "with a warning on stderr naming the file. A .bbw that records one keeps its own.")
      .def(
          "save",
          [](const Vocabulary& v, const Path& path, const std::string& format) {
            save_vocabulary(v, path.string(), parse_vocabulary_format(format));
          },
          py::arg("path"), py::arg("format") = "auto", py::call_guard<py::gil_scoped_release>(),
          "Save; format \"auto\" lets the extension choose (.bbw, .txt, .bin, .vins.bin,\n"
          ".yml.gz, .dbow3, .fbow), or name it as in load (\"vins\": VINS-Mono/VINS-Fusion's\n"
          "binary layout, 256-bit descriptors only).")
      .def_static("build", &build_vocabulary, py::arg("images"), py::arg("branching") = 10,
                  py::arg("levels") = 6, py::arg("weighting") = "tf-idf", py::arg("scoring") = "l1",
                  py::arg("seed") = 0, py::arg("threads") = 0, py::arg("descriptor") = "",
                  py::arg("stop_word_fraction") = 1.0, py::arg("max_iterations") = 20,
                  py::arg("progress") = py::none(),
                  "Train a vocabulary by hierarchical k-medians (k-means++ seeding).\n\n"
                  "images: one uint8 (n_i, code_size) array per training image (None: an image\n"
                  "without features); they define the IDF weights. descriptor names the\n"
                  "extractor (\"orb\", \"brief\", ...) to record. Words present in more than\n"
                  "stop_word_fraction of the images get weight 0. max_iterations bounds the\n"
                  "k-medians iterations per node. progress, if given, is called now and then\n"
                  "with a BuildProgress. The same seed gives the same vocabulary for any threads.")
      .def(
          "transform",
          [](const Vocabulary& v, const py::object& descriptors) {
            const Descriptors d = to_descriptors(descriptors, "descriptors", v.code_size());
            BowVector bow;
            py::gil_scoped_release release;
            v.transform(d.view, bow);
            return bow;
          },
          py::arg("descriptors"), "Descriptors (uint8 (n, code_size) array, or None) -> BowVector.")
      .def(
          "transform_with_features",
          [](const Vocabulary& v, const py::object& descriptors, const py::object& levels) {
            const auto levels_up = int_argument<unsigned>(levels, "levels_up");
            const Descriptors d = to_descriptors(descriptors, "descriptors", v.code_size());
            BowVector bow;
            FeatureVector fv;
            {
              py::gil_scoped_release release;
              v.transform(d.view, bow, fv, levels_up);
            }
            return py::make_tuple(bow, feature_vector_dict(fv));
          },
          py::arg("descriptors"), py::arg("levels_up") = 4,
          "Descriptors -> (BowVector, {node id: indices of the features under that node}),\n"
          "nodes levels_up levels above the words (DBoW2's direct index).")
      .def(
          "quantize",
          [](const Vocabulary& v, const py::object& descriptors) {
            const Descriptors d = to_descriptors(descriptors, "descriptors", v.code_size());
            py::array_t<WordId> words(static_cast<py::ssize_t>(d.view.rows));
            WordId* out = words.mutable_data();
            py::gil_scoped_release release;
            v.quantize(d.view, out);
            return words;
          },
          py::arg("descriptors"), "Word id of every descriptor (uint32 array).")
      .def("score", &Vocabulary::score, py::arg("a"), py::arg("b"),
           py::call_guard<py::gil_scoped_release>(),
           "Similarity of two BowVectors made by this vocabulary, with its scoring type.")
      .def_property_readonly("word_count", &Vocabulary::word_count, "Number of words (leaves).")
      .def_property_readonly("node_count", &Vocabulary::node_count,
                             "Number of tree nodes, root included.")
      .def_property_readonly("branching", &Vocabulary::branching, "k: children per node, at most.")
      .def_property_readonly("levels", &Vocabulary::levels, "L: depth of the deepest leaves.")
      .def_property_readonly("code_size", &Vocabulary::code_size, "Bytes per descriptor.")
      .def_property_readonly(
          "descriptor", &Vocabulary::descriptor,
          "Extractor that trained it (\"orb\", \"brief\", ...), \"\" if unknown.")
      .def_property_readonly(
          "weighting", [](const Vocabulary& v) { return to_string(v.weighting()); },
          "Word weighting: \"tf-idf\", \"tf\", \"idf\" or \"binary\".")
      .def_property_readonly(
          "scoring", [](const Vocabulary& v) { return to_string(v.scoring()); },
          "Scoring: \"l1\", \"l2\", \"chi-square\", \"kl\", \"bhattacharyya\" or \"dot-product\".")
      .def_property_readonly("checksum", &Vocabulary::checksum,
                             "CRC32C of the words: equal checksums, same vocabulary.")
      .def(
          "__repr__",
          [](const Vocabulary& v) { return "<binbow.Vocabulary " + v.description() + ">"; },
          "Shape and types as text.")
      .def(
          "__copy__", [](const Vocabulary& v) { return v; },
          "The same vocabulary (it is immutable; the tree is shared).")
      .def(
          "__deepcopy__", [](const Vocabulary& v, const py::object&) { return v; }, py::arg("memo"),
          "The same vocabulary (it is immutable; the tree is shared).")
      .def(py::pickle(&vocabulary_bytes, &vocabulary_from_bytes));

  py::class_<Database>(m, "Database",
                       "Inverted + direct index of images over a vocabulary. Thread-safe.")
      .def(py::init([](Vocabulary vocabulary, bool direct_index, const py::object& levels_up) {
             DatabaseOptions options;
             options.direct_index = direct_index;
             options.direct_index_levels_up = int_argument<unsigned>(levels_up, "levels_up");
             return Database(std::move(vocabulary), options);
           }),
           py::arg("vocabulary"), py::arg("direct_index") = true, py::arg("levels_up") = 4,
           "An empty database; with direct_index, each entry keeps its features grouped by\n"
           "the nodes levels_up levels above the words (for geometric checks).")
      .def("add", &add_descriptors, py::arg("descriptors"), py::arg("label") = py::none(),
           "Transform an image's descriptors (uint8 (n, code_size) array, or None for an\n"
           "image without features) and add it, with an optional label; returns its entry id.")
      .def(
          "add_bow",
          [](Database& db, const BowVector& bow, const py::object& label) {
            std::string text = label_argument(label);
            py::gil_scoped_release release;
            return db.add(bow, {}, std::move(text));
          },
          py::arg("bow"), py::arg("label") = py::none(),
          "Add an image already transformed with this database's vocabulary; returns its id.")
      .def("query", &query_database, py::arg("image"), py::arg("max_results") = 10,
           py::arg("max_entry_id") = py::none(), py::arg("fast") = false, py::kw_only(),
           py::arg("fast_candidates") = py::none(), py::arg("fast_candidate_share") = py::none(),
           py::arg("fast_min_postings") = py::none(),
           "Best matches of an image (a BowVector, or its descriptors: uint8 (n, code_size)\n"
           "array, or None) as a list of (entry, score, shared_words), best first; only\n"
           "entries with id <= max_entry_id when given. fast=True: candidates from the\n"
           "image's rarest words, each scored exactly (an entry can be missed, never\n"
           "misranked), for large databases; the first such query keeps a copy of every\n"
           "entry's words. fast_candidates (default 1000), fast_candidate_share (default\n"
           "a share that grows with the N entries, N/125 * (N/10**6)**0.3 candidates, where\n"
           "more) and fast_min_postings (default 2**20) trade\n"
           "speed for agreement with exact queries, as QueryOptions' fields of the same\n"
           "names. Runs without the GIL, on every core.")
      .def(
          "label",
          [](const Database& db, const py::object& entry) -> std::optional<std::string> {
            std::string label = db.label(existing_entry_id(db, entry, "label"));
            if (label.empty()) return std::nullopt;
            return label;
          },
          py::arg("entry"), "The entry's label, None if it has none (\"\" is no label).")
      .def(
          "set_label",
          [](Database& db, const py::object& entry, const std::string& label) {
            db.set_label(existing_entry_id(db, entry, "set_label"), label);
          },
          py::arg("entry"), py::arg("label"), "Set (or with \"\", remove) an entry's label.")
      .def(
          "remove",
          [](Database& db, const py::object& entry) {
            const EntryId id = existing_entry_id(db, entry, "remove");
            py::gil_scoped_release release;
            db.remove(id);
          },
          py::arg("entry"),
          "Remove an entry; its id is never reused. ValueError if it does not exist.")
      .def(
          "__contains__",
          [](const Database& db, const py::object& entry) {
            const std::optional<EntryId> id = entry_id(entry, "__contains__");
            return id && db.contains(*id);
          },
          py::arg("entry"), "Whether the entry exists.")
      .def("__len__", &Database::size, "Number of entries.")
      .def("__repr__", &database_repr, "Size and vocabulary as text.")
      .def("clear", &Database::clear, py::call_guard<py::gil_scoped_release>(),
           "Remove every entry; ids restart at 0.")
      .def(
          "feature_vector",
          [](const Database& db, const py::object& entry) {
            return feature_vector_dict(
                db.feature_vector(existing_entry_id(db, entry, "feature_vector")));
          },
          py::arg("entry"), "The entry's {node id: feature indices} (needs the direct index).")
      .def_property_readonly("next_entry_id", &Database::next_entry_id,
                             "The id the next add returns.")
      .def_property_readonly("memory_usage", &Database::memory_usage,
                             "Bytes of memory held by the index, the vocabulary excluded.")
      .def_property_readonly(
          "direct_index", [](const Database& db) { return db.options().direct_index; },
          "Whether entries keep their feature vectors.")
      .def_property_readonly(
          "levels_up", [](const Database& db) { return db.options().direct_index_levels_up; },
          "Levels above the words of the direct index's nodes.")
      .def_property_readonly("vocabulary", &Database::vocabulary, "The database's vocabulary.")
      .def(
          "save",
          [](const Database& db, const Path& path, bool include_vocabulary) {
            db.save(path.string(), include_vocabulary);
          },
          py::arg("path"), py::arg("include_vocabulary") = true,
          py::call_guard<py::gil_scoped_release>(),
          "Save as .bbdb; without the vocabulary, load it with Database.load(path, vocabulary).")
      .def(
          "save_incremental",
          [](const Database& db, const Path& path, bool include_vocabulary) {
            db.save_incremental(path.string(), include_vocabulary);
          },
          py::arg("path"), py::arg("include_vocabulary") = true,
          py::call_guard<py::gil_scoped_release>(),
          "Append the changes since the last save or load of path to its journal\n"
          "(path + \".journal\"), flushed to disk; a full save when the database was\n"
          "not last saved to or loaded from path, or the journal would pass a quarter\n"
          "of the file. Copy or remove the journal together with the .bbdb file.")
      .def(
          "append_journal",
          [](const Database& db, const Path& path) { return db.append_journal(path.string()); },
          py::arg("path"), py::call_guard<py::gil_scoped_release>(),
          "The append of save_incremental alone: True once the changes since the last\n"
          "save or load of path are in its journal (also when there were none); False,\n"
          "with nothing written, where save_incremental would save the whole file\n"
          "instead (then save it, under another name if path must not change).")
      .def_static(
          "load",
          [](const Path& path, const std::optional<Vocabulary>& vocabulary,
             const std::string& verification) {
            const DatabaseLoadOptions options = load_options(verification);
            return vocabulary ? Database::load(path.string(), *vocabulary, options)
                              : Database::load(path.string(), options);
          },
          py::arg("path"), py::arg("vocabulary") = py::none(),
          py::arg("verification") = "background", py::call_guard<py::gil_scoped_release>(),
          "Load a .bbdb file; a file saved without its vocabulary needs the same vocabulary.\n"
          "The file is mapped, not copied. verification=\"background\": the postings and\n"
          "the direct index are checked by a thread of their own while the database\n"
          "already answers (a damaged file may give wrong results until then; once the\n"
          "damage is found every call raises OSError naming the file); \"before-return\":\n"
          "everything is checked before load returns (OSError for a damaged file).")
      .def("wait_until_verified", &Database::wait_until_verified,
           py::call_guard<py::gil_scoped_release>(),
           "Wait for the background check of the file this database was loaded from;\n"
           "OSError naming the file and the damaged section if it is not intact. Returns\n"
           "at once when there is nothing to wait for.")
      .def("__copy__", &copy_database, "An independent copy sharing the vocabulary.")
      .def(
          "__deepcopy__", [](const Database& db, const py::object&) { return copy_database(db); },
          py::arg("memo"), "An independent copy sharing the (immutable) vocabulary.")
      .def(py::pickle([](const Database& db) { return database_bytes(db, true); },
                      [](const py::bytes& state) {
                        const auto [data, size] = bytes_of(state);
                        py::gil_scoped_release release;
                        return Database::deserialize(data, size, "<pickled binbow.Database>");
                      }));

  // The lock is the thread's that took it: release() and __exit__ must run
  // on that thread, as a with block does.
  struct HeldLock {
    std::optional<DatabaseLock> lock;
  };
  py::class_<HeldLock>(m, "DatabaseLock",
                       "One writer at a time for the database file at path: holds path +\n"
                       "\".lock\" (made beside the file) from construction until release()\n"
                       "or the end of a with block. Hold it from before Database.load until\n"
                       "after the save when other processes change the same database. Waits\n"
                       "up to `wait` seconds for another writer (0: not at all), then raises\n"
                       "binbow.WriteConflict naming it.")
      .def(py::init([](const Path& path, double wait) {
             py::gil_scoped_release release;
             auto held = std::make_unique<HeldLock>();
             held->lock.emplace(path.string(), wait);
             return held;
           }),
           py::arg("path"), py::arg("wait") = 0.0,
           "Take the writer lock of the database at path, waiting up to `wait` seconds.")
      .def(
          "release", [](HeldLock& held) { held.lock.reset(); }, "Let other writers in.")
      .def(
          "__enter__", [](HeldLock& lock) -> HeldLock& { return lock; },
          py::return_value_policy::reference)
      .def(
          "__exit__",
          [](HeldLock& held, const py::object&, const py::object&, const py::object&) {
            held.lock.reset();
            return false;
          },
          py::arg("type"), py::arg("value"), py::arg("traceback"));
}

}  // namespace binbow::python
