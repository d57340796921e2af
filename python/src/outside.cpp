// Points outside the control mesh, reported from Python as `mbi deform` reports them: mbi.OutsideWarning,
// and max_outside= refusing those too far out (interp/outside.hpp has the rule and the sentences).
#include "bindings.hpp"

#include <mbi/interp/outside.hpp>

namespace mbi::python {
namespace {

py::handle outside_warning;  // mbi.OutsideWarning, made in bind_outside (lives as long as the module)

}  // namespace

void report_outside(const interp::Embedding& emb, const Input& p, std::optional<double> max_outside) {
  if (max_outside) {
    const interp::FarPoints far = interp::far_points(emb, p.map, *max_outside);
    if (far.count > 0) throw Error("P: " + interp::far_points_message(far, "max_outside=", "(U, T)"));
  }
  if (emb.outside.empty()) return;
  // stack level 2: past the wrapper of mbi/_errors.py around every function, to the caller's line
  if (PyErr_WarnEx(outside_warning.ptr(), interp::outside_message(emb).c_str(), 2) < 0)
    throw py::error_already_set();  // warnings as errors
}

void bind_outside(py::module_& m) {
  outside_warning = PyErr_NewExceptionWithDoc("mbi._mbi.OutsideWarning",
                                              "Dense points outside the control mesh, extrapolated from the nearest "
                                              "element (max_outside= of Deformer, FramePipeline and embed refuses "
                                              "those too far out).",
                                              PyExc_UserWarning, nullptr);
  if (!outside_warning) throw py::error_already_set();
  m.attr("OutsideWarning") = outside_warning;
}

}  // namespace mbi::python
