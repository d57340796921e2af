// Simulator step time (mbi::sim). Reference set-up of the issue (VegaFEM corotational linear
// FEM, implicit backward Euler, one Newton iteration): dt = 1/60 s, E = 1e5 Pa, nu = 0.45,
// 1000 kg/m^3, bar with one end fixed, gravity. Vega measured 1.41 ms at 281 tets, 10.6 ms at
// 1,311 tets and 54.9 ms at 5,125 tets on this kind of machine.
//
//   mbi-bench --benchmark_filter=BM_SimStep
//
// Arguments: (mesh, solver, tol) with mesh 0..3 = about 100, 1.3K, 5K, 20K tetrahedra, solver
// 1 = LDLT (cached symbolic analysis), 2 = PCG (3x3 block-Jacobi, warm-started), and PCG
// relative residual tolerance 10^-tol (Vega's PCG uses 1e-6). Counters: tets, Newton and PCG
// iterations per step, assembly and solve time per step (ms).
#include "bench_common.hpp"

#include <benchmark/benchmark.h>
#include <mbi/generate/procedural.hpp>
#include <mbi/sim/simulator.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <vector>

namespace {

struct BarMesh {
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
};

// Bar of nx x n x n cells (cell size 0.1 m), each hex split into 6 tetrahedra.
BarMesh bar_mesh(int nx, int n) {
  BarMesh M;
  mbi::generate::box_tets(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.1 * nx, 0.1 * n, 0.1 * n),
                        Eigen::Vector3i(nx, n, n), M.U, M.T);
  return M;
}

BarMesh bench_mesh(int which) {
  switch (which) {
    case 0: return bar_mesh(4, 2);    //    96 tets
    case 1: return bar_mesh(14, 4);   //  1344 tets
    case 2: return bar_mesh(24, 6);   //  5184 tets
    default: return bar_mesh(34, 10); // 20400 tets
  }
}

// Fixes the bar's x = 0 end, takes `warm` steps (the bar starts to sag), then times one step
// per benchmark iteration and sets the per-step counters.
void time_steps(benchmark::State& state, mbi::sim::Simulator& sim, const BarMesh& M, int warm) {
  std::vector<int> fixed;
  for (Eigen::Index i = 0; i < M.U.rows(); ++i)
    if (M.U(i, 0) == 0.0) fixed.push_back(static_cast<int>(i));
  sim.fix(fixed);
  for (int s = 0; s < warm; ++s) sim.step();
  double newton = 0, iters = 0, assemble = 0, solve = 0;
  long steps = 0;
  for (auto _ : state) {
    const mbi::sim::StepResult r = sim.step();
    if (!r.success) {
      state.SkipWithError(r.message.c_str());
      break;
    }
    newton += r.newton_iterations;
    iters += r.solver_iterations;
    assemble += r.assemble_ms;
    solve += r.solve_ms;
    ++steps;
  }
  const double k = steps > 0 ? 1.0 / static_cast<double>(steps) : 0.0;
  state.counters["tets"] = static_cast<double>(M.T.rows());
  state.counters["newton_per_step"] = newton * k;
  state.counters["pcg_iters_per_step"] = iters * k;
  state.counters["assemble_ms"] = assemble * k;
  state.counters["solve_ms"] = solve * k;
}

void BM_SimStep(benchmark::State& state) {
  const BarMesh M = bench_mesh(static_cast<int>(state.range(0)));
  mbi::sim::Parameters p;
  p.dt = 1.0 / 60.0;
  p.newton_iterations = 1;
  p.solver = state.range(1) == 1 ? mbi::sim::LinearSolver::LDLT : mbi::sim::LinearSolver::PCG;
  p.pcg_tolerance = std::pow(10.0, -static_cast<double>(state.range(2)));
  mbi::sim::Simulator sim(M.U, M.T, mbi::sim::Material{1e5, 0.45, 1000.0}, p);
  time_steps(state, sim, M, 5);
}

// Quick mode (CI): the two smaller meshes only.
void sim_args(benchmark::internal::Benchmark* b) {
  const int meshes = mbi::bench::quick() ? 2 : 4;
  for (int m = 0; m < std::min(meshes, 3); ++m) b->Args({m, 1, 8});
  for (int m = 0; m < meshes; ++m)
    for (int tol : {6, 8}) b->Args({m, 2, tol});
}

BENCHMARK(BM_SimStep)->ArgNames({"mesh", "solver", "tol"})->Apply(sim_args)
    ->Unit(benchmark::kMillisecond)->MinTime(mbi::bench::min_time(0.5));

// The step against size on the PCG path (tolerance 1e-6, as Vega's and SOFA's CG solvers use):
// bars of 4n x n x n cells, 5K to 527K tetrahedra, built once per size. Counters as above,
// plus the set-up (Simulator construction: rest data, the pattern's analysis) in seconds.
//
//   mbi-bench --benchmark_filter=BM_SimStepSize
void BM_SimStepSize(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));  // cells across; the bar is 4n long
  const BarMesh M = bar_mesh(4 * n, n);
  mbi::sim::Parameters p;
  p.dt = 1.0 / 60.0;
  p.newton_iterations = 1;
  p.solver = mbi::sim::LinearSolver::PCG;
  p.pcg_tolerance = 1e-6;
  const auto t0 = std::chrono::steady_clock::now();
  mbi::sim::Simulator sim(M.U, M.T, mbi::sim::Material{1e5, 0.45, 1000.0}, p);
  const double setup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  time_steps(state, sim, M, 3);
  state.counters["setup_s"] = setup_s;
}

// 24 n^3 tetrahedra: n = 6, 10, 16, 22, 28 give 5K, 24K, 98K, 256K, 527K; quick mode: 6 alone.
void size_args(benchmark::internal::Benchmark* b) {
  for (int n : {6, 10, 16, 22, 28}) {
    b->Args({n});
    if (mbi::bench::quick()) break;
  }
}

BENCHMARK(BM_SimStepSize)->ArgNames({"cells"})->Apply(size_args)->Unit(benchmark::kMillisecond)
    ->MinTime(mbi::bench::min_time(1.0));

}  // namespace
