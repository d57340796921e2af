// Modified-BI cost per stage (mbi::interp): per-frame solve (sparse triangular solves vs dense
// operator, fact 11), Bezier control points and embedding. Precompute against the control-vertex
// count is in bench_scaling.cpp, evaluation of the embedded points in bench_throughput.cpp.
//
//   mbi-bench --benchmark_filter='BM_Interp'
//
// Meshes (argument `mesh`): 0 = twisted bar 8x2x2 unit cells (81 vertices, 192 tets),
// 1 = box cage 7x7x6 cells (448 vertices, 1764 tets), 2 = box cage 10x10x10 cells
// (1331 vertices, 6000 tets).
#include <benchmark/benchmark.h>
#include <mbi/interp.hpp>

#include "common/grid_meshes.hpp"
#include "bench_common.hpp"

#include <random>

namespace {

using mbi::interp::BezierPoints;
using mbi::interp::ModifiedBI;
using mbi::interp::Options;
using mbi::interp::SolvePath;

struct Scene {
  mbi::test::Mesh mesh;
  Eigen::MatrixXd X;
};

const Scene& scene(int id) {
  static Scene scenes[3];
  static bool built[3] = {false, false, false};
  if (!built[id]) {
    Scene& s = scenes[id];
    if (id == 0) s.mesh = mbi::test::box_tet_mesh(8, 2, 2, Eigen::Vector3d(8, 2, 2));
    if (id == 1) s.mesh = mbi::test::box_tet_mesh(7, 7, 6, Eigen::Vector3d(7, 7, 6));
    if (id == 2) s.mesh = mbi::test::box_tet_mesh(10, 10, 10, Eigen::Vector3d(10, 10, 10));
    s.X = mbi::test::twist_bend(s.mesh.U, 1.5707963267948966, 0.1);
    built[id] = true;
  }
  return scenes[id];
}

// Arguments: (mesh, path) with path 1 = sparse triangular solves, 2 = dense operator.
void BM_InterpSolve(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  Options o;
  o.solve_path = state.range(1) == 2 ? SolvePath::Dense : SolvePath::Sparse;
  const ModifiedBI mbi(s.mesh.U, s.mesh.T, o);
  for (auto _ : state) {
    mbi::interp::VertexMatrices M = mbi.solve(s.X);
    benchmark::DoNotOptimize(M.data());
  }
  state.counters["unknowns"] = mbi.unknowns();
}
BENCHMARK(BM_InterpSolve)
    ->Args({0, 1})->Args({0, 2})->Args({1, 1})->Args({1, 2})->Args({2, 1})->Args({2, 2})
    ->Unit(benchmark::kMicrosecond)->MinTime(mbi::bench::min_time());

void BM_InterpBezier(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  const ModifiedBI mbi(s.mesh.U, s.mesh.T);
  const mbi::interp::VertexMatrices M = mbi.solve(s.X);
  BezierPoints B = mbi.bezier(s.X, M);  // written in place each frame, as a Deformer's scratch is
  for (auto _ : state) {
    mbi::interp::bezier_points(s.mesh.U, s.mesh.T, s.X, M, B);
    benchmark::DoNotOptimize(B.data());
  }
  state.counters["tets"] = static_cast<double>(s.mesh.T.rows());
}
BENCHMARK(BM_InterpBezier)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->MinTime(mbi::bench::min_time());

void BM_InterpEmbed(benchmark::State& state) {
  const Scene& s = scene(1);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> ux(-0.5, 7.5), uz(-0.5, 6.5);
  Eigen::MatrixXd P(static_cast<Eigen::Index>(state.range(0)), 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) P.row(i) << ux(rng), ux(rng), uz(rng);
  for (auto _ : state) {
    mbi::interp::Embedding emb = mbi::interp::embed(s.mesh.U, s.mesh.T, P);
    benchmark::DoNotOptimize(emb.bary.data());
    state.counters["outside"] = static_cast<double>(emb.outside.size());
  }
  state.SetItemsProcessed(state.iterations() * P.rows());
}
BENCHMARK(BM_InterpEmbed)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time());

}  // namespace
