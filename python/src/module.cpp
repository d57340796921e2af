// mbi._mbi: the extension module of the Python package mbi (python/mbi/__init__.py re-exports it).
#include "bindings.hpp"

#include <mbi/interp/modified_bi.hpp>

PYBIND11_MODULE(_mbi, m) {
  namespace py = pybind11;
  m.doc() = "mbi's C++ libraries (modified barycentric interpolation); use the package mbi.";
  // every error of the libraries, and every refused argument: a ValueError carrying the message
  py::register_exception<mbi::Error>(m, "Error", PyExc_ValueError);
  mbi::python::bind_embedding(m);
  mbi::python::bind_methods(m);
  mbi::python::bind_evaluate(m);
  mbi::python::bind_deformer(m);
  mbi::python::bind_timing(m);
}
