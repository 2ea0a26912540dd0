// The compiled part of the `binbow` Python package, imported as binbow._binbow
// and re-exported by binbow/__init__.py (which adds Vocabulary.default and the
// pure-Python helpers). Each room of the library has its binding files
// (bind_core.cpp, bind_vision.cpp, bind_params.cpp, bind_loop.cpp,
// bind_evaluation.cpp); binding.h lists them and the strict input
// conversions they share.
//
// The GIL is released around every call that does real work, so threads run
// in parallel.
#include <pybind11/pybind11.h>

#include <exception>

#include "binbow/error.h"
#include "binding.h"

namespace py = pybind11;

PYBIND11_MODULE(_binbow, m) {
  m.doc() =
      "Bags of binary words for fast place recognition (Galvez-Lopez & Tardos 2012).\n\n"
      "The compiled part of the binbow package: import binbow, not binbow._binbow.";
  m.attr("__version__") = BINBOW_VERSION;
  // Classes and their signatures are named after the public package
  // (binbow.Vocabulary), which is also where pickle finds them again.
  m.attr("__module__") = "binbow";

  static py::exception<binbow::Error> error(m, "Error", PyExc_RuntimeError);
  error.attr("__module__") = "binbow";
  error.doc() =
      "A binbow error that is neither a bad argument (ValueError) nor a file problem (OSError).";
  static py::exception<binbow::WriteConflict> conflict(m, "WriteConflict", PyExc_OSError);
  conflict.attr("__module__") = "binbow";
  conflict.doc() =
      "A save refused because another writer holds the database or saved it since it was\n"
      "loaded (an OSError): nothing was written; load again and redo the change.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const binbow::WriteConflict& e) {
      conflict(e.what());
    } catch (const binbow::InvalidArgument& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const binbow::FileError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    } catch (const binbow::Error& e) {
      error(e.what());
    }
  });

  binbow::python::bind_core(m);
  binbow::python::bind_vision(m);
  binbow::python::bind_params(m);
  binbow::python::bind_evaluation(m);
  binbow::python::bind_loop(m);

  py::delattr(m, "__module__");
}
