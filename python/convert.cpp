#include "binding.h"

#include <string>

#include "binbow/error.h"

namespace binbow::python {

std::string type_name(const py::handle& object) {
  return py::str(py::type::of(object).attr("__name__")).cast<std::string>();
}

double float_option(const py::handle& value, const std::string& name) {
  if (PyBool_Check(value.ptr()) || !(PyFloat_Check(value.ptr()) || PyLong_Check(value.ptr())))
    throw py::type_error(name + " must be a float, got " + type_name(value));
  return value.cast<double>();
}

py::int_ int_of(const py::handle& value, const std::string& name) {
  if (PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr()))
    throw py::type_error(name + " must be an int, got " + type_name(value));
  const auto number = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  if (!number) throw py::error_already_set();
  return number;
}

std::string int_text(const py::int_& number) {
  // Python refuses to write out ints of more than 4300 digits.
  const auto bits = number.attr("bit_length")().cast<std::size_t>();
  if (bits <= 256) return py::str(py::handle(number)).cast<std::string>();
  return std::string(PyObject_RichCompareBool(number.ptr(), py::int_(0).ptr(), Py_LT) == 1
                         ? "a negative"
                         : "an") +
         " int of " + std::to_string(bits) + " bits";
}

bool int_in_range(const py::int_& number, const py::int_& low, const py::int_& high) {
  const int above_low = PyObject_RichCompareBool(number.ptr(), low.ptr(), Py_GE);
  const int below_high = PyObject_RichCompareBool(number.ptr(), high.ptr(), Py_LE);
  if (above_low < 0 || below_high < 0) throw py::error_already_set();
  return above_low == 1 && below_high == 1;
}

std::string shape_of(const py::array& array) {
  std::string shape = "(";
  for (py::ssize_t i = 0; i < array.ndim(); ++i)
    shape += (i ? ", " : "") + std::to_string(array.shape(i));
  return shape + (array.ndim() == 1 ? ",)" : ")");
}

py::array checked_uint8_array(const py::handle& object, const std::string& what) {
  if (!py::isinstance<py::array>(object))
    throw py::type_error(what + " must be a numpy uint8 array, got " + type_name(object));
  auto array = py::reinterpret_borrow<py::array>(object);
  if (array.dtype().kind() != 'u' || array.dtype().itemsize() != 1)
    throw py::type_error(what + " must be a numpy uint8 array, got dtype " +
                         py::str(array.dtype()).cast<std::string>() +
                         " (binary descriptors are bytes; convert explicitly if that is meant)");
  return array;
}

py::array_t<std::uint8_t, py::array::c_style> contiguous_uint8(const py::array& array,
                                                               const std::string& what) {
  if (array.flags() & py::array::c_style)
    return py::reinterpret_borrow<py::array_t<std::uint8_t, py::array::c_style>>(array);
  // A strided view may stand for far more bytes than it holds (a broadcast
  // row has stride 0): its size is checked before anything is allocated.
  // Its dtype and shape are fine, so it is not a bad argument (ValueError)
  // but a limit of binbow's: binbow.Error.
  const auto bytes = static_cast<std::size_t>(array.size());
  if (bytes > kMaxCopiedBytes)
    throw Error(what + " (dtype " + py::str(array.dtype()).cast<std::string>() + ", shape " +
                shape_of(array) + ") is not C-contiguous and too large to copy (" +
                std::to_string(bytes) + " bytes, at most " + std::to_string(kMaxCopiedBytes) +
                "); pass C-contiguous rows (numpy.ascontiguousarray)");
  auto copy = py::array_t<std::uint8_t, py::array::c_style>::ensure(array);
  if (!copy)
    throw py::value_error(what + " (dtype " + py::str(array.dtype()).cast<std::string>() +
                          ", shape " + shape_of(array) +
                          ") could not be copied into C-contiguous rows");
  return copy;
}

Descriptors to_descriptors(const py::handle& object, const std::string& what,
                           std::size_t code_size) {
  Descriptors out;
  out.view.code_size = code_size;
  if (object.is_none()) return out;
  const py::array array = checked_uint8_array(object, what);
  if (array.ndim() != 2)
    throw py::value_error(
        what + " must be 2-D with one row per feature, shape (n, code_size); got shape " +
        shape_of(array));
  const auto columns = static_cast<std::size_t>(array.shape(1));
  if (code_size != 0 && columns != code_size)
    throw py::value_error(what + " have " + std::to_string(columns) + " bytes (" +
                          std::to_string(columns * 8) + " bits) per row, the vocabulary's words " +
                          std::to_string(code_size) + " bytes (" + std::to_string(code_size * 8) +
                          " bits): wrong descriptor type for this vocabulary?");
  out.array = contiguous_uint8(array, what);
  out.view = {out.array.data(), static_cast<std::size_t>(out.array.shape(0)), columns};
  return out;
}

py::bytes to_bytes(const std::vector<std::uint8_t>& bytes) {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

std::pair<const std::uint8_t*, std::size_t> bytes_of(const py::bytes& bytes) {
  char* data = nullptr;
  py::ssize_t size = 0;
  if (PYBIND11_BYTES_AS_STRING_AND_SIZE(bytes.ptr(), &data, &size) != 0)
    throw py::error_already_set();
  return {reinterpret_cast<const std::uint8_t*>(data), static_cast<std::size_t>(size)};
}

}  // namespace binbow::python
