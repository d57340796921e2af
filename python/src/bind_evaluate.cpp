// Evaluation of the dense points from element Bezier points: exact (evaluate), the float kernel
// (FastEvaluator), and the transposes a vector-Jacobian product is made of.
#include "bindings.hpp"

#include <mbi/interp/adjoint.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/interp/fast_evaluate.hpp>

namespace mbi::python {
namespace {

using interp::Embedding;
using interp::FastEvaluator;
using Fast = Guarded<FastEvaluator>;

// Bezier points of an embedding's elements: ((m K), d) with m at least the largest element used.
Input bezier_points_arg(const py::handle& B, int d, bool finite) {
  if (d != 2 && d != 3) throw Error("the embedding must be 2D or 3D");
  return float_matrix(B, "B", {-1, d}, finite);
}

py::object evaluate_exact(const py::object& B, const Embedding& emb, const py::object& out,
                          const py::object& rest_normals, const py::object& normals_out, int threads) {
  const Input b = bezier_points_arg(B, emb.dim(), true);
  Output pos = float_output(out, "out", emb.size(), emb.dim());
  check_disjoint(pos, {&b});
  if (rest_normals.is_none()) {
    if (!normals_out.is_none()) throw Error("normals_out needs rest_normals");
    without_gil([&] { interp::evaluate<double>(b.map, emb, pos.map, threads); });
    return pos.finish();
  }
  const Input n = float_matrix(rest_normals, "rest_normals", {emb.size(), emb.dim()});
  Output nrm = float_output(normals_out, "normals_out", emb.size(), emb.dim());
  check_disjoint(pos, {&n});
  check_disjoint(nrm, {&b, &n});
  check_disjoint(pos, nrm);
  without_gil([&] { interp::evaluate<double>(b.map, emb, n.map, pos.map, nrm.map, threads); });
  return py::make_tuple(pos.finish(), nrm.finish());
}

std::unique_ptr<Fast> make_fast(const Embedding& emb, int threads, const std::string& simd) {
  const interp::Simd s = interp::kSimdNames.parse(simd, "simd");
  return without_gil([&] { return std::make_unique<Fast>(emb, threads, s); });
}

py::object evaluate_fast(Fast& f, const py::object& B, const py::object& out, bool normals,
                         const py::object& normals_out) {
  const FastEvaluator& fe = f.object;
  // B is read as given (no NaN check: this is the per-frame kernel; a NaN gives NaN points)
  const Input b = bezier_points_arg(B, fe.dim(), false);
  Output32 pos = float32_output(out, "out", fe.size(), fe.dim());
  check_disjoint(pos, {&b});
  if (!normals && normals_out.is_none()) {
    f.run([&](FastEvaluator& e) { e.evaluate(b.map, pos.map.data(), nullptr); });
    return pos.finish();
  }
  Output32 nrm = float32_output(normals_out, "normals_out", fe.size(), fe.dim());
  check_disjoint(nrm, {&b});
  check_disjoint(pos, nrm);
  f.run([&](FastEvaluator& e) { e.evaluate(b.map, pos.map.data(), nrm.map.data()); });
  return py::make_tuple(pos.finish(), nrm.finish());
}

void bind_fast_evaluator(py::module_& m) {
  using namespace pybind11::literals;
  py::class_<Fast>(m, "FastEvaluator",
                   "The compact float kernel for one embedding: all cores, no allocation per call, results "
                   "as float32 (p, d) arrays.")
      .def(py::init(&make_fast), "embedding"_a, py::kw_only(), "threads"_a = 0, "simd"_a = "auto",
           "threads: 0 = all cores; simd: auto, avx512, avx2 or portable.")
      .def(
          "set_rest_normals",
          [](Fast& f, const py::object& N) {
            const Input n = float_matrix(N, "normals", {f.object.size(), f.object.dim()});
            f.run([&](FastEvaluator& e) { e.set_rest_normals(n.map); });
          },
          "normals"_a, "Unit rest normals (p, d), needed for evaluate(..., normals=True).")
      .def("evaluate", &evaluate_fast, "B"_a, py::kw_only(), "out"_a = py::none(), "normals"_a = false,
           "normals_out"_a = py::none(),
           "Positions (p, d) float32 from Bezier points B ((m K), d); with normals (or normals_out) also the "
           "mapped unit normals: (positions, normals). out, normals_out: float32 (p, d) arrays to "
           "write into. B is not checked for NaN.")
      .def_property_readonly("dim", [](Fast& f) { return f.object.dim(); })
      .def_property_readonly("size", [](Fast& f) { return f.object.size(); }, "p")
      .def_property_readonly("elements", [](Fast& f) { return f.object.elements(); })
      .def_property_readonly("threads", [](Fast& f) { return f.object.threads(); })
      .def_property_readonly("simd", [](Fast& f) { return std::string(FastEvaluator::name(f.object.simd())); })
      .def_property_readonly("coherent", [](Fast& f) { return f.object.coherent(); })
      .def_property_readonly("sorted_by_element", [](Fast& f) { return f.object.sorted_by_element(); },
                             "True when the evaluator keeps its points sorted by element (random order over a "
                             "large mesh) and scatters the results to their rows")
      .def_property_readonly("has_rest_normals", [](Fast& f) { return f.run([](FastEvaluator& e) { return e.has_rest_normals(); }); })
      .def("bytes_per_point", [](Fast& f, bool normals) { return f.object.bytes_per_point(normals); },
           "normals"_a = false)
      .def_static(
          "supported", [](const std::string& simd) { return FastEvaluator::supported(interp::kSimdNames.parse(simd, "simd")); },
          "simd"_a, "Whether this CPU runs the kernels of simd (auto, avx512, avx2, portable).");
}

}  // namespace

void bind_evaluate(py::module_& m) {
  using namespace pybind11::literals;
  m.def("evaluate", &evaluate_exact, "B"_a, "embedding"_a, py::kw_only(), "out"_a = py::none(),
        "rest_normals"_a = py::none(), "normals_out"_a = py::none(), "threads"_a = 0,
        "Exact (float64) positions (p, d) of the embedded points from element Bezier points B ((m K), d). "
        "With rest_normals (p, d): (positions, normals). out, normals_out: float64 (p, d) arrays to write into.");
  bind_fast_evaluator(m);
  m.def(
      "evaluate_transpose",
      [](const Embedding& emb, const py::object& G, int elements, int threads) {
        const Input g = float_matrix(G, "G", {emb.size(), emb.dim()}, false);
        return to_numpy(without_gil([&] { return interp::evaluate_transpose(emb, g.map, elements, threads); }));
      },
      "embedding"_a, "G"_a, "elements"_a, py::kw_only(), "threads"_a = 0,
      "The transpose of evaluate(): dL/dB ((m K), d) from G = dL/dpositions (p, d); m = elements.");
  m.def(
      "bezier_transpose",
      [](const py::object& U, const py::object& T, const py::object& G) {
        const Mesh c = control_mesh(U, T);
        const Input g = float_matrix(G, "G", {-1, c.U.map.cols()});
        interp::BezierTranspose t = without_gil([&] { return interp::bezier_transpose(c.U.map, c.T, g.map); });
        return py::make_tuple(c_order(t.X), to_numpy(std::move(t.M)));
      },
      "U"_a, "T"_a, "G"_a,
      "The transpose of bezier_points(): (dL/dX (n, d), dL/dM ((n d), d)) from G = dL/dB ((m K), d).");
}

}  // namespace mbi::python
