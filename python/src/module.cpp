// mbi._mbi: the extension module of the Python package mbi (python/mbi/__init__.py re-exports it).
#include "bindings.hpp"

#include <mbi/interp/modified_bi.hpp>
#include <mbi/io/io.hpp>

namespace {

// The errors of the file readers and writers (the message names the file): mbi.FileError, an
// mbi.Error (a ValueError, as every error of the libraries) and an OSError, so that both
// `except mbi.Error` and `except OSError` catch a missing or malformed file.
void register_file_error(pybind11::module_& m, const pybind11::handle& error) {
  namespace py = pybind11;
  static py::handle type;  // lives as long as the module (never freed, as pybind11's own)
  type = PyErr_NewExceptionWithDoc("mbi._mbi.FileError", "A file mbi could not read or write (names the file).",
                                   py::make_tuple(error, py::handle(PyExc_OSError)).ptr(), nullptr);
  if (!type) throw py::error_already_set();
  m.attr("FileError") = type;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const mbi::io::Error& e) {
      PyErr_SetString(type.ptr(), e.what());
    }
  });
}

}  // namespace

PYBIND11_MODULE(_mbi, m) {
  namespace py = pybind11;
  m.doc() = "mbi's C++ libraries (modified barycentric interpolation); use the package mbi.";
  // every error of the libraries, and every refused argument: a ValueError carrying the message
  auto& error = py::register_exception<mbi::Error>(m, "Error", PyExc_ValueError);
  register_file_error(m, error);
  mbi::python::bind_outside(m);
  mbi::python::bind_embedding(m);
  mbi::python::bind_methods(m);
  mbi::python::bind_memory(m);
  mbi::python::bind_evaluate(m);
  mbi::python::bind_deformer(m);
#ifdef MBI_PYTHON_TIMING
  mbi::python::bind_timing(m);
#else
  m.attr("_timing") = py::none();  // the benchmark's clocks are in a module built with MBI_PYTHON_TIMING
#endif
  mbi::python::bind_sim(m);
  mbi::python::bind_pipeline(m);
  mbi::python::bind_contact(m);
  mbi::python::bind_io(m);
  mbi::python::bind_cage(m);
  mbi::python::bind_scene(m);
}
