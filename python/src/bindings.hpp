#pragma once
// The parts of the extension module mbi._mbi, one file each, and what they share.
#include "arrays.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <pybind11/stl.h>  // std::vector and std::string arguments and results

#include <mutex>
#include <optional>
#include <utility>

namespace mbi::python {

void bind_outside(py::module_& m);     // outside.cpp: OutsideWarning
void bind_embedding(py::module_& m);   // bind_embedding.cpp: Embedding, embed, mesh helpers
void bind_methods(py::module_& m);     // bind_methods.cpp: ModifiedBI, Phong, Bezier points, metrics
void bind_evaluate(py::module_& m);    // bind_evaluate.cpp: evaluate, FastEvaluator, transposes
void bind_deformer(py::module_& m);    // bind_deformer.cpp: Deformer
void bind_timing(py::module_& m);      // timing.cpp: C++ baselines of the overhead benchmark (MBI_PYTHON_TIMING)
void bind_sim(py::module_& m);         // bind_sim.cpp: Simulator
void bind_pipeline(py::module_& m);    // bind_pipeline.cpp: FramePipeline and its drivers
void bind_contact(py::module_& m);     // bind_contact.cpp: Collider, FramePipeline with contact (after bind_pipeline)
void bind_io(py::module_& m);          // bind_io.cpp: file readers and writers
void bind_cage(py::module_& m);        // bind_cage.cpp: cage
void bind_scene(py::module_& m);       // bind_scene.cpp: run_scene
void bind_memory(py::module_& m);      // bind_memory.cpp: estimate_memory, memory_limit

/// The max_memory argument: None -> 0 (the memory there is), bytes > 0, or a size such as "8G"
/// (interp::parse_memory_size); anything else an Error naming it.
double max_memory_arg(const py::object& value);

/// Points of P outside the control mesh (emb.outside), as `mbi deform` reports them: Error for
/// those farther out than max_outside x the model size, else an mbi.OutsideWarning at the
/// caller's line. Needs the GIL.
void report_outside(const interp::Embedding& emb, const Input& p, std::optional<double> max_outside);

#ifdef MBI_PYTHON_TIMING
/// Seconds the calling thread last spent in a section without the GIL: the C++ part of its last
/// call, which python/bench/overhead.py subtracts from the call's time seen from Python.
inline thread_local double last_section_seconds = 0;

/// Records the time from its construction to its destruction in last_section_seconds.
struct SectionClock {
  Clock::time_point t0 = Clock::now();
  ~SectionClock() { last_section_seconds = ms_since(t0) * 1e-3; }
};
#else
struct SectionClock {};  // the shipped module reads no clock (CMake MBI_PYTHON_TIMING)
#endif

/// Runs f() without the GIL (every call that does real work), so that other Python threads run
/// meanwhile; nothing in f may touch a Python object.
template <class F>
auto without_gil(F&& f) {
  py::gil_scoped_release release;
  [[maybe_unused]] SectionClock clock;
  return f();
}

/// A control-sized result (M, Bezier points) that compute(target) writes into an
/// interp::MatrixOut (releasing the GIL itself): a new Eigen matrix handed over without a copy
/// when out is None (Fortran order, which FastEvaluator reads in place), else out itself, of
/// either order (rows x cols, checked before compute() runs, against the call's inputs too).
template <class F>
py::array result(const py::handle& out, Eigen::Index rows, Eigen::Index cols, std::initializer_list<const Input*> inputs,
                 F&& compute) {
  if (out.is_none()) {
    Eigen::MatrixXd A(rows, cols);
    compute(interp::MatrixOut(A));
    return to_numpy(std::move(A));
  }
  Output o = float_output(out, "out", rows, cols);
  check_disjoint(o, inputs);
  compute(interp::MatrixOut(o.map));
  return o.finish();
}

/// A pose or M read where it is when its columns are contiguous (Fortran order), else copied
/// into a matrix kept per thread: what the methods' Eigen::Ref<const MatrixXd> takes without the
/// temporary it would allocate for a C-order array.
inline Eigen::Ref<const Eigen::MatrixXd> kept_columns(const Input& in) {
  thread_local Eigen::MatrixXd copy;
  return columns(in.map, copy);
}

/// An object whose calls change state it keeps (a FastEvaluator's per-call terms, a Deformer's
/// evaluator): one call at a time. The lock is taken after the GIL is released and let go
/// before it is taken back, so that a thread waiting here never holds the GIL.
template <class T>
struct Guarded {
  template <class... A>
  explicit Guarded(A&&... args) : object(std::forward<A>(args)...) {}
  template <class F>
  auto run(F&& f) {
    py::gil_scoped_release release;
    [[maybe_unused]] SectionClock clock;
    std::lock_guard<std::mutex> lock(mutex);
    return f(object);
  }
  T object;
  std::mutex mutex;
};

}  // namespace mbi::python
