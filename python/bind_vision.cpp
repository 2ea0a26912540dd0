// The vision room: binbow.FeatureExtractor, the extractors of the CLI
// (vision::make_extractor and its options) on image files or numpy images.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "binding.h"

namespace binbow::python {
namespace {

// As the CLI's --features: far above any useful count, it only keeps absurd
// values away from OpenCV.
constexpr int kMaxFeatures = 1000000;

// The options each extractor takes besides max_features, as keywords.
const std::vector<std::string>& option_names(const std::string& descriptor) {
  static const std::vector<std::string> orb = {"scale_factor", "levels", "fast_threshold",
                                               "edge_threshold"};
  static const std::vector<std::string> brief = {"fast_threshold", "non_max_suppression", "pattern",
                                                 "keep_border_corners"};
  static const std::vector<std::string> none;
  if (descriptor == "orb") return orb;
  if (descriptor == "brief") return brief;
  return none;
}

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

// Python's int, not bool (a subclass of int) nor float: a count given as 2.5
// or True is a mistake, not something to round (int_argument).
int int_option(const py::handle& value, const std::string& name, int low, int high) {
  return int_argument<int>(value, name, low, high);
}

bool bool_option(const py::handle& value, const std::string& name) {
  if (!PyBool_Check(value.ptr()))
    throw py::type_error(name + " must be a bool, got " + type_name(value));
  return value.cast<bool>();
}

// Names are case-insensitive ("ORB" is "orb"), as the CLI's --descriptor.
std::string lower_case(std::string name) {
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

bool is_path(const py::handle& object) {
  return py::isinstance<py::str>(object) || py::isinstance<py::bytes>(object) ||
         py::hasattr(object, "__fspath__");
}

// str, bytes or os.PathLike as the file system's string.
std::string path_string(const py::handle& object) {
  return py::module_::import("os").attr("fsdecode")(object).cast<std::string>();
}

// A FeatureExtractor made from Python arguments, which it keeps for repr and pickle.
class PythonExtractor {
 public:
  PythonExtractor(std::string descriptor, const py::object& max_features,
                  const py::object& max_image_pixels, py::dict options)
      : descriptor_(lower_case(std::move(descriptor))), options_(std::move(options)) {
    if (!max_features.is_none())
      max_features_ = int_option(max_features, "max_features", 1, kMaxFeatures);
    if (!max_image_pixels.is_none())
      max_image_pixels_ = int_argument<std::uint64_t>(max_image_pixels, "max_image_pixels", 1,
                                                      std::numeric_limits<std::uint64_t>::max());
    const std::vector<std::string> names = vision::extractor_names();
    if (std::find(names.begin(), names.end(), descriptor_) == names.end())
      throw py::value_error("unknown descriptor '" + descriptor_ + "'; expected one of " +
                            joined(names));
    const std::vector<std::string>& known = option_names(descriptor_);
    std::vector<std::string> unknown;
    for (const auto& [key, value] : options_) {
      const std::string name = key.cast<std::string>();
      if (std::find(known.begin(), known.end(), name) == known.end()) unknown.push_back(name);
    }
    if (!unknown.empty())
      throw py::type_error("FeatureExtractor(descriptor=\"" + descriptor_ +
                           "\") got unknown option(s) " + joined(unknown) + "; " +
                           (known.empty() ? descriptor_ + " takes none besides max_features"
                                          : descriptor_ + " takes " + joined(known)));
    extractor_ = make();
  }

  const std::string& descriptor() const { return descriptor_; }
  std::optional<int> max_features() const { return max_features_; }
  std::uint64_t max_image_pixels() const { return max_image_pixels_; }
  const py::dict& options() const { return options_; }
  const vision::FeatureExtractor& extractor() const { return *extractor_; }
  // For holders that outlive this object (a loop::SequenceDetector).
  std::shared_ptr<const vision::FeatureExtractor> shared() const { return extractor_; }

 private:
  std::shared_ptr<const vision::FeatureExtractor> make() const {
    const auto option = [this](const char* name) -> py::object {
      return options_.contains(name) ? py::object(options_[name]) : py::object();
    };
    if (descriptor_ == "orb") {
      vision::OrbOptions options;
      if (max_features_) options.max_features = *max_features_;
      if (const auto v = option("scale_factor"))
        options.scale_factor = static_cast<float>(float_option(v, "scale_factor"));
      if (const auto v = option("levels")) options.levels = int_option(v, "levels", 1, 32);
      if (const auto v = option("fast_threshold"))
        options.fast_threshold = int_option(v, "fast_threshold", 0, 255);
      if (const auto v = option("edge_threshold"))
        options.edge_threshold = int_option(v, "edge_threshold", 0, 1000);
      return vision::make_orb_extractor(options);
    }
    if (descriptor_ == "brief") {
      vision::BriefOptions options;
      if (max_features_) options.max_features = *max_features_;
      if (const auto v = option("fast_threshold"))
        options.fast_threshold = int_option(v, "fast_threshold", 0, 255);
      if (const auto v = option("non_max_suppression"))
        options.non_max_suppression = bool_option(v, "non_max_suppression");
      if (const auto v = option("keep_border_corners"))
        options.keep_border_corners = bool_option(v, "keep_border_corners");
      if (const auto v = option("pattern")) {
        if (!is_path(v)) throw py::type_error("pattern must be a path, got " + type_name(v));
        options.pattern_file = path_string(v);
      }
      py::gil_scoped_release release;  // reads the pattern file
      return vision::make_brief_extractor(options);
    }
    return vision::make_extractor(descriptor_, max_features_.value_or(0));
  }

  std::string descriptor_;
  std::optional<int> max_features_;
  std::uint64_t max_image_pixels_ = vision::kDefaultMaxImagePixels;
  py::dict options_;
  std::shared_ptr<const vision::FeatureExtractor> extractor_;
};

// A grey (H, W), BGR (H, W, 3) or BGRA (H, W, 4) uint8 image, kept alive
// while `image` views it. It is only read, so read-only arrays are fine.
struct Image {
  py::array_t<std::uint8_t, py::array::c_style> array;
  cv::Mat image;  // grey, or BGR/BGRA until converted
};

Image image_from_array(const py::handle& object, std::uint64_t max_pixels) {
  if (!py::isinstance<py::array>(object))
    throw py::type_error("image must be a path (str or os.PathLike) or a numpy uint8 array, got " +
                         type_name(object));
  const auto array = py::reinterpret_borrow<py::array>(object);
  if (array.dtype().kind() != 'u' || array.dtype().itemsize() != 1)
    throw py::type_error("image must be a numpy uint8 array, got dtype " +
                         py::str(array.dtype()).cast<std::string>() +
                         " (8-bit pixels; convert explicitly if that is meant)");
  if (!(array.ndim() == 2 || (array.ndim() == 3 && (array.shape(2) == 3 || array.shape(2) == 4))))
    throw py::value_error("image must be grey (H, W), BGR (H, W, 3) or BGRA (H, W, 4), got shape " +
                          shape_of(array));
  const auto height = static_cast<std::uint64_t>(array.shape(0));
  const auto width = static_cast<std::uint64_t>(array.shape(1));
  if (height != 0 && width > max_pixels / height)
    throw py::value_error("image of shape " + shape_of(array) + " has " +
                          std::to_string(width * height) + " pixels, more than the limit of " +
                          std::to_string(max_pixels) + " (FeatureExtractor(max_image_pixels=...))");
  if (height > INT_MAX || width > INT_MAX)
    throw py::value_error("image of shape " + shape_of(array) + " is larger than OpenCV takes");
  Image out;
  out.array = contiguous_uint8(array, "image");
  const int type = array.ndim() == 2 ? CV_8UC1 : CV_8UC(static_cast<int>(array.shape(2)));
  out.image = cv::Mat(static_cast<int>(height), static_cast<int>(width), type,
                      const_cast<std::uint8_t*>(out.array.data()));
  return out;
}

py::array_t<float> keypoint_array(const std::vector<vision::Keypoint>& keypoints) {
  py::array_t<float> out({static_cast<py::ssize_t>(keypoints.size()), py::ssize_t{6}});
  auto rows = out.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < rows.shape(0); ++i) {
    const vision::Keypoint& k = keypoints[static_cast<std::size_t>(i)];
    rows(i, 0) = k.x;
    rows(i, 1) = k.y;
    rows(i, 2) = k.size;
    rows(i, 3) = k.angle;
    rows(i, 4) = k.response;
    rows(i, 5) = static_cast<float>(k.octave);
  }
  return out;
}

py::array_t<std::uint8_t> descriptor_array(const DescriptorMatrix& descriptors) {
  py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(descriptors.rows()),
                                 static_cast<py::ssize_t>(descriptors.code_size())});
  if (descriptors.rows() > 0)
    std::copy(descriptors.data(), descriptors.data() + descriptors.rows() * descriptors.code_size(),
              out.mutable_data());
  return out;
}

py::tuple extract(const PythonExtractor& self, const py::object& image) {
  vision::Features features;
  if (is_path(image)) {
    const std::string path = path_string(image);
    py::gil_scoped_release release;
    features = self.extractor().extract(vision::read_grey_image(path, self.max_image_pixels()));
  } else {
    Image input = image_from_array(image, self.max_image_pixels());
    py::gil_scoped_release release;
    if (input.image.channels() != 1) {
      cv::Mat grey;
      cv::cvtColor(input.image, grey,
                   input.image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
      input.image = grey;
    }
    features = self.extractor().extract(input.image);
  }
  return py::make_tuple(keypoint_array(features.keypoints), descriptor_array(features.descriptors));
}

std::string extractor_repr(const PythonExtractor& self) {
  std::string text = "binbow.FeatureExtractor(descriptor=\"" + self.descriptor() + "\"";
  if (self.max_features()) text += ", max_features=" + std::to_string(*self.max_features());
  if (self.max_image_pixels() != vision::kDefaultMaxImagePixels)
    text += ", max_image_pixels=" + std::to_string(self.max_image_pixels());
  for (const auto& [key, value] : self.options())
    text += ", " + key.cast<std::string>() + "=" + py::repr(value).cast<std::string>();
  return text + ")";
}

}  // namespace

std::shared_ptr<const vision::FeatureExtractor> extractor_of(const py::handle& object) {
  if (!py::isinstance<PythonExtractor>(object)) return nullptr;
  return object.cast<const PythonExtractor&>().shared();
}

void bind_vision(py::module_& m) {
  py::class_<PythonExtractor>(
      m, "FeatureExtractor",
      "Keypoints and binary descriptors of images: the CLI's extractors with its defaults.\n\n"
      "descriptor (case-insensitive): \"orb\" (OpenCV ORB, 32 bytes), \"brief\" (the paper's "
      "BRIEF, bit for bit\n"
      "DLoopDetector's, 32 bytes), \"akaze\" (61 bytes) or \"brisk\" (64 bytes).\n"
      "max_features: the strongest keypoints kept; None: the extractor's default (ORB 1000,\n"
      "BRIEF 300, AKAZE and BRISK every keypoint found).\n"
      "Options: orb takes scale_factor, levels, fast_threshold, edge_threshold; brief takes\n"
      "fast_threshold, non_max_suppression, pattern (a YAML/XML pattern file, as the CLI's\n"
      "--pattern) and keep_border_corners (describe corners whose tests leave the image, those\n"
      "tests giving 0 bits, as DLib's BRIEF does; default False); akaze and brisk take none.\n"
      "An unknown option is a TypeError. max_image_pixels: the largest image extract takes,\n"
      "as a file or an array (default 100 million pixels, as the CLI).\n"
      "Immutable: extract may be called from several threads at once.")
      .def(py::init([](const std::string& descriptor, const py::object& max_features,
                       const py::object& max_image_pixels, const py::kwargs& options) {
             return std::make_unique<PythonExtractor>(descriptor, max_features, max_image_pixels,
                                                      py::dict(options));
           }),
           py::arg("descriptor") = "orb", py::arg("max_features") = py::none(),
           py::arg("max_image_pixels") = py::none(),
           "An extractor of the given descriptor type; see the class docstring for options.")
      .def("extract", &extract, py::arg("image"),
           "(keypoints, descriptors) of an image: a path (str or os.PathLike, read as the CLI\n"
           "reads images, in grey) or a numpy uint8 array (read-only is fine), grey (H, W),\n"
           "BGR (H, W, 3) as cv2.imread returns, or BGRA (H, W, 4). keypoints: float32 (N, 6) rows "
           "x, y, size, angle, response,\n"
           "octave; descriptors: uint8 (N, code_size), row i describing keypoint i. An image\n"
           "without corners gives N = 0 (arrays of that shape, not None).")
      .def_property_readonly("descriptor", &PythonExtractor::descriptor,
                             "The descriptor type: \"orb\", \"brief\", \"akaze\" or \"brisk\".")
      .def_property_readonly(
          "code_size", [](const PythonExtractor& self) { return self.extractor().code_size(); },
          "Bytes per descriptor (32 for ORB and BRIEF, 61 AKAZE, 64 BRISK).")
      .def_property_readonly("max_features", &PythonExtractor::max_features,
                             "The keypoints kept, None for the extractor's default.")
      .def_property_readonly(
          "options", [](const PythonExtractor& self) { return py::dict(self.options()); },
          "The options given besides descriptor and max_features (a copy).")
      .def_property_readonly("max_image_pixels", &PythonExtractor::max_image_pixels,
                             "The largest image extract accepts, in pixels (file or array).")
      .def("__repr__", &extractor_repr, "The constructor call that makes this extractor.")
      .def(py::pickle(
          [](const PythonExtractor& self) {
            return py::make_tuple(self.descriptor(), self.max_features(), self.options(),
                                  self.max_image_pixels());
          },
          [](const py::tuple& state) {
            // Three fields: pickled before max_image_pixels existed.
            if (state.size() != 3 && state.size() != 4)
              throw py::value_error("invalid pickled binbow.FeatureExtractor");
            return std::make_unique<PythonExtractor>(
                state[0].cast<std::string>(), py::object(state[1]),
                state.size() == 4 ? py::object(state[3]) : py::object(py::none()),
                state[2].cast<py::dict>());
          }));
}

}  // namespace binbow::python
