// Deformer: bind once (embedding + precompute), then deform poses or batches of them, with
// normals, in float64 (exact) or float32 (the fast kernel), and the vector-Jacobian product.
#include "bindings.hpp"

#include <mbi/pipeline/deformer.hpp>

#include <cmath>
#include <cstdio>

namespace mbi::python {
namespace {

using pipeline::Deformer;
using Bound = Guarded<Deformer>;

std::unique_ptr<Bound> make_deformer(const py::object& U, const py::object& T, const py::object& P,
                                     const std::string& method, std::optional<double> alpha, double beta, bool pin_boundary,
                                     const py::object& rest_normals, int threads, std::optional<double> max_outside,
                                     const py::object& max_memory) {
  const Mesh c = control_mesh(U, T);
  const Input p = float_matrix(P, "P", {-1, c.U.map.cols()});
  pipeline::DeformerOptions o;
  o.method = pipeline::kMethodNames.parse(method, "method");
  o.interp.alpha = alpha;
  o.interp.beta = beta;
  o.interp.pin_boundary = pin_boundary;
  o.interp.max_memory = max_memory_arg(max_memory);
  o.threads = threads;
  Eigen::MatrixXd normals;
  if (!rest_normals.is_none()) normals = float_matrix(rest_normals, "rest_normals", {p.map.rows(), p.map.cols()}).map;
  auto bound = without_gil([&] { return std::make_unique<Bound>(c.U.map, c.T, p.map, o, normals); });
  report_outside(bound->object.embedding(), p, max_outside);
  return bound;
}

// float32 results (the fast kernel) when out is float32 or dtype asks for it; float64 otherwise
// (float_output and float32_output check out's dtype and layout).
bool wants_float32(const py::object& out, const py::object& dtype) {
  auto is_float = [](const py::dtype& dt, py::ssize_t bytes) { return dt.kind() == 'f' && dt.itemsize() == bytes; };
  if (!out.is_none()) return py::isinstance<py::array>(out) && is_float(py::reinterpret_borrow<py::array>(out).dtype(), 4);
  if (dtype.is_none()) return false;
  py::dtype dt;
  try {
    dt = py::dtype::from_args(dtype);
  } catch (py::error_already_set& e) {
    throw Error(std::string("dtype: ") + e.what());
  }
  if (is_float(dt, 4) || is_float(dt, 8)) return is_float(dt, 4);
  throw Error("dtype must be float64 (exact) or float32 (the fast kernel), not " + py::str(dt).cast<std::string>());
}

// The fast kernel's float32 positions (and normals) of each pose of x.
py::object deform_float(Bound& b, const Input& x, Frames frames, const py::object& out, bool normals,
                        const py::object& normals_out) {
  const Eigen::Index n = b.object.vertices(), p = b.object.points(), d = b.object.dim();
  Output32 pos = float32_output(out, "out", p, d, frames);
  check_disjoint(pos, {&x});
  if (!normals) {
    b.run([&](Deformer& e) {
      for (Eigen::Index k = 0; k < frames.count; ++k)
        e.deform_float(x.map.middleRows(k * n, n), pos.map.middleRows(k * p, p));
    });
    return pos.finish();
  }
  Output32 nrm = float32_output(normals_out, "normals_out", p, d, frames);
  check_disjoint(nrm, {&x});
  check_disjoint(pos, nrm);
  b.run([&](Deformer& e) {
    for (Eigen::Index k = 0; k < frames.count; ++k)
      e.deform_float(x.map.middleRows(k * n, n), pos.map.middleRows(k * p, p), nrm.map.middleRows(k * p, p));
  });
  return py::make_tuple(pos.finish(), nrm.finish());
}

py::object deform(Bound& b, const py::object& X, const py::object& out, bool normals,
                  const py::object& normals_out, const py::object& dtype) {
  const Eigen::Index n = b.object.vertices(), p = b.object.points(), d = b.object.dim();
  Frames frames;
  const Input x = float_batch(X, "X", {n, d}, frames);
  normals = normals || !normals_out.is_none();
  if (wants_float32(out, dtype)) return deform_float(b, x, frames, out, normals, normals_out);
  Output pos = float_output(out, "out", p, d, frames);
  check_disjoint(pos, {&x});
  if (!normals) {
    b.run([&](Deformer& e) { e.deform_batch(x.map, pos.map); });
    return pos.finish();
  }
  Output nrm = float_output(normals_out, "normals_out", p, d, frames);
  check_disjoint(nrm, {&x});
  check_disjoint(pos, nrm);
  b.run([&](Deformer& e) {
    for (Eigen::Index k = 0; k < frames.count; ++k)
      e.deform(x.map.middleRows(k * n, n), pos.map.middleRows(k * p, p), nrm.map.middleRows(k * p, p));
  });
  return py::make_tuple(pos.finish(), nrm.finish());
}

py::object vjp(Bound& b, const py::object& G, const py::object& out) {
  const Eigen::Index n = b.object.vertices(), p = b.object.points(), d = b.object.dim();
  Frames frames;
  const Input g = float_batch(G, "G", {p, d}, frames, false);  // the C++ call names a non-finite row
  Output o = float_output(out, "out", n, d, frames);
  check_disjoint(o, {&g});
  b.run([&](Deformer& e) { e.vjp_batch(g.map, o.map); });
  return o.finish();
}

}  // namespace

void bind_deformer(py::module_& m) {
  using namespace pybind11::literals;
  py::class_<Bound>(m, "Deformer",
                    "Bind once, deform many: the dense points P embedded in a rest control mesh (U, T) and the "
                    "method's precompute, made once; deform() maps poses X (n, d) to positions (p, d).")
      .def(py::init(&make_deformer), "U"_a, "T"_a, "P"_a, py::kw_only(), "method"_a = "modified-bi", "alpha"_a = py::none(),
           "beta"_a = 0.0, "pin_boundary"_a = false, "rest_normals"_a = py::none(), "threads"_a = 0,
           "max_outside"_a = py::none(), "max_memory"_a = py::none(),
           "U (n, d) rest control vertices, T (m, d+1) elements, P (p, d) dense rest points (units of U). method: "
           "bi, modified-bi or phong; alpha (None: 0.1 in 3D, 0.2 in 2D), beta (0: automatic), pin_boundary: modified-BI's; rest_normals: unit "
           "normals (p, d) for deform(..., normals=True); threads: 0 = all cores. Points outside the control mesh "
           "warn (mbi.OutsideWarning); max_outside refuses those farther out than max_outside x the model size "
           "(the diagonal of P's bounding box), as mbi deform --max-outside. max_memory: bytes or a size such as '8G' "
           "that modified-BI's factor may take (else its iterative path; None: the memory available).")
      .def("deform", &deform, "X"_a, py::kw_only(), "out"_a = py::none(), "normals"_a = false,
           "normals_out"_a = py::none(), "dtype"_a = py::none(),
           "Positions (p, d) of pose X (n, d), or (frames, p, d) of a batch X (frames, n, d). normals: also the "
           "mapped unit normals, as (positions, normals). dtype float64 (default, exact) or float32 (the fast "
           "kernel); out, normals_out: arrays to write into (their dtype decides).")
      .def("vjp", &vjp, "G"_a, py::kw_only(), "out"_a = py::none(),
           "dL/dX (n, d) from G = dL/dpositions (p, d) (or a batch: (frames, p, d) -> (frames, n, d)): the "
           "transpose of deform(), exact; positions are linear in X for every method.")
      .def(
          "M",
          [](Bound& b, const py::object& X) {
            const Input x = float_matrix(X, "X", {b.object.vertices(), b.object.dim()});
            return to_numpy(b.run([&](Deformer& e) { return e.M(x.map); }));
          },
          "X"_a, "The method's M ((n d), d) at pose X (0 for BI).")
      .def(
          "bezier",
          [](Bound& b, const py::object& X) {
            const Input x = float_matrix(X, "X", {b.object.vertices(), b.object.dim()});
            return to_numpy(b.run([&](Deformer& e) { return e.bezier(x.map); }));
          },
          "X"_a, "The element Bezier points ((m K), d) at pose X.")
      .def(
          "set_alpha", [](Bound& b, double alpha) { b.run([&](Deformer& e) { e.set_alpha(alpha); }); }, "alpha"_a,
          "Changes modified-BI's alpha (> 0) and refactors.")
      .def_property_readonly(
          "embedding", [](Bound& b) -> const interp::Embedding& { return b.object.embedding(); },
          py::return_value_policy::reference_internal)
      .def_property_readonly("method", [](Bound& b) { return std::string(pipeline::method_name(b.object.method())); })
      .def_property_readonly("dim", [](Bound& b) { return b.object.dim(); })
      .def_property_readonly("vertices", [](Bound& b) { return b.object.vertices(); }, "n")
      .def_property_readonly("elements", [](Bound& b) { return b.object.elements(); }, "m")
      .def_property_readonly("points", [](Bound& b) { return b.object.points(); }, "p")
      .def_property_readonly("outside_points", [](Bound& b) { return b.object.embedding().outside.size(); },
                             "how many points lie outside the control mesh (extrapolated from the nearest element)")
      .def_property_readonly("max_outside_distance", [](Bound& b) { return b.object.embedding().max_outside_distance; },
                             "the farthest outside point's distance to the control mesh (units of P; 0 when none)")
      .def_property_readonly("has_rest_normals", [](Bound& b) { return b.object.has_rest_normals(); })
      .def_property_readonly("alpha", [](Bound& b) { return b.run([](Deformer& e) { return e.solver().alpha(); }); },
                             "modified-BI's alpha (mbi.Error for the other methods)")
      .def_property_readonly("beta", [](Bound& b) { return b.run([](Deformer& e) { return e.solver().beta(); }); },
                             "modified-BI's beta (mbi.Error for the other methods)")
      .def_property_readonly(
          "memory_bytes",
          [](Bound& b) { return b.run([](Deformer& e) { return e.solver().memory_bytes(); }); },
          "bytes modified-BI's precompute keeps (mbi.Error for the other methods)");
}

}  // namespace mbi::python
