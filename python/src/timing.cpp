// mbi._mbi._timing: the C++ side of the overhead benchmark (python/bench/overhead.py): the
// seconds of the C++ part of the last call (last_call), and C++ loops that time `calls` calls of
// a C++ call in C++ (no Python in between), one clock reading before and after each.
#include "bindings.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/interp/fast_evaluate.hpp>
#include <mbi/interp/modified_bi.hpp>
#include <mbi/pipeline/deformer.hpp>

#include <vector>

namespace mbi::python {
namespace {

template <class T, class F>
py::array time_calls(Guarded<T>& object, int calls, F&& call) {
  if (calls < 1) throw Error("calls must be >= 1");
  std::vector<double> seconds(static_cast<size_t>(calls));
  object.run([&](T&) {
    for (double& s : seconds) {
      const auto t0 = Clock::now();
      call();
      s = ms_since(t0) * 1e-3;
    }
  });
  py::array_t<double> out(calls);
  std::copy(seconds.begin(), seconds.end(), out.mutable_data());
  return out;
}

}  // namespace

void bind_timing(py::module_& m) {
  using namespace pybind11::literals;
  py::module_ t = m.def_submodule("_timing", "C++ baselines of the overhead benchmark (python/bench/overhead.py)");
  t.def(
      "last_call", [] { return last_section_seconds; },
      "Seconds the last call of this thread spent in C++ without the GIL (the C++ call it wraps).");
  t.def(
      "solve",
      [](Guarded<interp::ModifiedBI>& s, const py::object& X, int calls) {
        // what a C++ caller holds: X as an Eigen matrix, M returned by value
        const Eigen::MatrixXd x = float_matrix(X, "X", {s.object.vertices(), s.object.dim()}).map;
        return time_calls(s, calls, [&] {
          const interp::VertexMatrices M = s.object.solve(x);
          (void)M;
        });
      },
      "solver"_a, "X"_a, "calls"_a, "Seconds of each of `calls` calls of ModifiedBI::solve(X) in C++.");
  t.def(
      "fast_evaluate",
      [](Guarded<interp::FastEvaluator>& f, const py::object& B, const py::object& out, int calls) {
        // B read in place, as FastEvaluator.evaluate reads it
        const Input b = float_matrix(B, "B", {-1, f.object.dim()}, false);
        Output32 o = float32_output(out, "out", f.object.size(), f.object.dim());  // o.array keeps it alive
        float* const positions = o.map.data();
        const auto seconds = time_calls(f, calls, [&] { f.object.evaluate(b.map, positions, nullptr); });
        o.finish();
        return seconds;
      },
      "evaluator"_a, "B"_a, "out"_a, "calls"_a,
      "Seconds of each of `calls` calls of FastEvaluator::evaluate(B, positions) in C++ into out.");
  t.def(
      "deform",
      [](Guarded<pipeline::Deformer>& d, const py::object& X, const py::object& out, int calls) {
        const Eigen::MatrixXd x = float_matrix(X, "X", {d.object.vertices(), d.object.dim()}).map;
        Output o = float_output(out, "out", d.object.points(), d.object.dim());
        const auto seconds = time_calls(d, calls, [&] { d.object.deform(x, o.map); });
        o.finish();
        return seconds;
      },
      "deformer"_a, "X"_a, "out"_a, "calls"_a,
      "Seconds of each of `calls` calls of Deformer::deform(X, positions) in C++ into out.");
  t.def(
      "vjp",
      [](Guarded<pipeline::Deformer>& d, const py::object& G, const py::object& out, int calls) {
        const Eigen::MatrixXd g = float_matrix(G, "G", {d.object.points(), d.object.dim()}).map;
        Output o = float_output(out, "out", d.object.vertices(), d.object.dim());
        const auto seconds = time_calls(d, calls, [&] { d.object.vjp_batch(g, o.map); });
        o.finish();
        return seconds;
      },
      "deformer"_a, "G"_a, "out"_a, "calls"_a,
      "Seconds of each of `calls` calls of Deformer::vjp_batch(G, out) in C++ into out.");
}

}  // namespace mbi::python
