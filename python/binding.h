// Conversions between Python objects and binbow's types shared by the
// binding files (bind_core.cpp, bind_vision.cpp, bind_params.cpp, bind_loop.cpp,
// bind_evaluation.cpp).
//
// Inputs are taken strictly: a numpy array of the wrong dtype is a TypeError
// naming it and a wrong shape a ValueError, never a silent conversion (float
// SIFT descriptors or out-of-range values would turn into wrong bits). Only
// a non-contiguous array is copied, within kMaxCopiedBytes.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "binbow/descriptors.h"

namespace binbow::vision {
class FeatureExtractor;
}

namespace binbow::python {

namespace py = pybind11;
using Path = std::filesystem::path;

// The Python type name of `object`, for error messages.
std::string type_name(const py::handle& object);
// A float argument (an int is taken too, a bool is not): TypeError otherwise.
double float_option(const py::handle& value, const std::string& name);

// An integer argument, taken here rather than by pybind11, whose conversion
// of an int past its C++ type raises RuntimeError "Unable to cast" (or, for
// a parameter of that type, a TypeError listing every argument, descriptor
// arrays included): an int or a numpy integer, not a bool or a float
// (TypeError naming `name`).
py::int_ int_of(const py::handle& value, const std::string& name);
// The int as Python writes it, or its size when too long to write out.
std::string int_text(const py::int_& number);
// Whether low <= number <= high, whatever the number's size.
bool int_in_range(const py::int_& number, const py::int_& low, const py::int_& high);

// int_of within [low, high], as T: ValueError naming `name` and the range
// otherwise, however large the int.
template <typename T>
T int_argument(const py::handle& value, const std::string& name,
               T low = std::numeric_limits<T>::min(), T high = std::numeric_limits<T>::max()) {
  const py::int_ number = int_of(value, name);
  if (!int_in_range(number, py::int_(low), py::int_(high)))
    throw py::value_error(name + " must be in [" + std::to_string(low) + ", " +
                          std::to_string(high) + "], got " + int_text(number));
  return number.cast<T>();
}
// "(3, 32)", "(5,)": an array's shape as Python writes it.
std::string shape_of(const py::array& array);

// The uint8 array of one image's descriptors: `what` names it in errors
// ("descriptors", "images[3]").
py::array checked_uint8_array(const py::handle& object, const std::string& what);

// Arrays that are not C-contiguous are copied, up to this many bytes: a view
// of more (a numpy broadcast or as_strided view can stand for terabytes) is a
// ValueError asking for C-contiguous rows, never an attempt to allocate it.
constexpr std::size_t kMaxCopiedBytes = std::size_t{1} << 31;

// `array` (uint8) as C-contiguous rows: itself, or a bounded copy.
py::array_t<std::uint8_t, py::array::c_style> contiguous_uint8(const py::array& array,
                                                               const std::string& what);

// Descriptors of one image received from Python, kept alive while the view is used.
struct Descriptors {
  py::array_t<std::uint8_t, py::array::c_style> array;  // null for None
  DescriptorView view;
};

// `code_size`: the size the caller needs (the vocabulary's), 0 when any size
// fits (training). None, what OpenCV returns for an image without keypoints,
// becomes an empty view of that size.
Descriptors to_descriptors(const py::handle& object, const std::string& what,
                           std::size_t code_size);

py::bytes to_bytes(const std::vector<std::uint8_t>& bytes);
// The bytes of a pickled state; `data` stays valid while `bytes` lives.
std::pair<const std::uint8_t*, std::size_t> bytes_of(const py::bytes& bytes);

// The extractor of a binbow.FeatureExtractor object; null when `object` is not one.
std::shared_ptr<const vision::FeatureExtractor> extractor_of(const py::handle& object);

// The binding of each room of the library, called by module.cpp in this order
// (a class is registered before the signatures that name it).
void bind_core(py::module_& m);
void bind_vision(py::module_& m);
void bind_params(py::module_& m);
void bind_evaluation(py::module_& m);
void bind_loop(py::module_& m);

}  // namespace binbow::python
