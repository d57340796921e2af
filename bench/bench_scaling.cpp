// How the modified-BI precompute and per-frame solve grow with the control-vertex count, and
// how long embedding a million points takes.
//
//   build/release/mbi-bench --benchmark_filter='BM_Scale|BM_Embed'
//
// Control meshes: boxes of unit cells, 6 tetrahedra a cell (generate::box_tets), twisted and
// bent: 2x2x3 cells (36 vertices), 4x4x3 (100), 7x7x6 (448), 10x10x10 (1,331), 12x12x11 (2,028),
// 21x21x20 (10,164). Precompute = the interp::ModifiedBI constructor (assembly of E_vibr and
// E_disc, beta, gauge, sparse Cholesky factorisation); solve = ModifiedBI::solve (all M_i for
// one X, the automatic solve path). The 10K precompute takes minutes with Eigen's SimplicialLLT:
// it runs once, and only in the full run (not with MBI_BENCH_QUICK).
#include "bench_common.hpp"

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <map>
#include <memory>

namespace {

struct Box {
  Eigen::MatrixXd U, X;
  Eigen::MatrixXi T;
};

Eigen::Vector3i cells_for(int control) {
  switch (control) {
    case 35: return {2, 2, 3};
    case 100: return {4, 4, 3};
    case 450: return {7, 7, 6};
    case 1300: return {10, 10, 10};
    case 2000: return {12, 12, 11};
    default: return {21, 21, 20};
  }
}

const Box& box(int control) {
  static std::map<int, std::unique_ptr<Box>> cache;
  auto& slot = cache[control];
  if (slot) return *slot;
  slot = std::make_unique<Box>();
  const Eigen::Vector3i n = cells_for(control);
  mbi::generate::box_tets(Eigen::Vector3d::Zero(), n.cast<double>(), n, slot->U, slot->T);
  slot->X = mbi::generate::twist_bend(slot->U, 0.5 * n.x(), 0.5 * n.y(), 0, n.z(), 1.2, 0.1);
  return *slot;
}

// The last precompute of each size, kept for the solve benchmark (the 10K one is expensive).
std::map<int, std::unique_ptr<mbi::interp::ModifiedBI>>& solvers() {
  static std::map<int, std::unique_ptr<mbi::interp::ModifiedBI>> s;
  return s;
}

void counters(benchmark::State& st, const Box& b) {
  st.counters["control"] = static_cast<double>(b.U.rows());
  st.counters["tets"] = static_cast<double>(b.T.rows());
}

// Arguments: nominal control-vertex count (35, 100, 450, 1300, 2000, 10000) and the
// factorization (cholmod 0 = Eigen SimplicialLLT, 1 = CHOLMOD supernodal). Counters: the factor's
// nonzeros and the memory the precompute keeps (MB).
void BM_ScalePrecompute(benchmark::State& st) {
  const int control = static_cast<int>(st.range(0));
  const Box& b = box(control);
  mbi::interp::Options o;
  o.factorization = st.range(1) ? mbi::interp::Factorization::Cholmod : mbi::interp::Factorization::Eigen;
  std::unique_ptr<mbi::interp::ModifiedBI> last;
  for (auto _ : st) {
    last.reset();  // hand the previous factor back first (memory at 10K)
    last = std::make_unique<mbi::interp::ModifiedBI>(b.U, b.T, o);
    benchmark::DoNotOptimize(last->beta());
  }
  st.counters["unknowns"] = last->unknowns();
  st.counters["factor_nnz"] = static_cast<double>(last->factor_nonzeros());
  st.counters["memory_mb"] = static_cast<double>(last->memory_bytes()) / 1e6;
  st.counters["dense_operator"] = last->dense_operator() ? 1 : 0;
  st.SetLabel(last->factorization());
  counters(st, b);
  solvers()[control] = std::move(last);
}

void BM_ScaleSolve(benchmark::State& st) {
  const int control = static_cast<int>(st.range(0));
  const Box& b = box(control);
  auto& s = solvers()[control];
  if (!s) s = std::make_unique<mbi::interp::ModifiedBI>(b.U, b.T);
  for (auto _ : st) {
    mbi::interp::VertexMatrices M = s->solve(b.X);
    benchmark::DoNotOptimize(M.data());
  }
  st.counters["dense_operator"] = s->dense_operator() ? 1 : 0;
  st.counters["factor_nnz"] = static_cast<double>(s->factor_nonzeros());
  st.SetLabel(s->factorization());
  counters(st, b);
  if (control >= 10000) s.reset();  // hand the 10K factor's memory back
}

// One registration per size and factorization: the large precomputes run exactly once
// (Iterations(1)), the small ones long enough to average. Eigen's SimplicialLLT at 10K takes
// about 100 s: it runs only with MBI_BENCH_EIGEN_10K=1. The solve runs on the last precompute of
// its size (CHOLMOD's when the build has it, as Factorization::Automatic picks).
[[maybe_unused]] const bool registered = [] {
  const bool eigen_10k = std::getenv("MBI_BENCH_EIGEN_10K") != nullptr;
  for (int c : {35, 100, 450, 1300, 2000, 10000}) {
    if (mbi::bench::quick() && c > 1300) continue;
    for (int cholmod : {0, 1}) {
      if (cholmod && !mbi::interp::cholmod_available()) continue;
      if (!cholmod && c >= 10000 && !eigen_10k && mbi::interp::cholmod_available()) continue;
      if (!cholmod && c >= 1300 && mbi::bench::quick()) continue;
      auto* p = benchmark::RegisterBenchmark("BM_ScalePrecompute", BM_ScalePrecompute);
      p->ArgNames({"control", "cholmod"})->Args({c, cholmod})->Unit(benchmark::kMillisecond)->UseRealTime();
      if (c >= 2000) p->Iterations(1);
      else p->MinTime(mbi::bench::min_time(0.3));
    }
    benchmark::RegisterBenchmark("BM_ScaleSolve", BM_ScaleSolve)
        ->ArgName("control")->Arg(c)->Unit(benchmark::kMicrosecond)->UseRealTime()
        ->MinTime(mbi::bench::min_time(0.3));
  }
  return true;
}();

}  // namespace

namespace {

// Embedding 1M random points (100K in quick mode) in box control meshes of 450 (5x5x3 cells) and
// 5,082 (11x11x7 cells) tetrahedra. The points lie inside, as a dense model lies inside its cage
// (BM_InterpEmbed in bench_interp.cpp measures a cloud with a third of its points outside).
void BM_Embed(benchmark::State& st) {
  const long long p = st.range(0);
  const Eigen::Vector3i n = st.range(1) < 1000 ? Eigen::Vector3i(5, 5, 3) : Eigen::Vector3i(11, 11, 7);
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  mbi::generate::box_tets(Eigen::Vector3d::Zero(), n.cast<double>(), n, U, T);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> uni(0.001, 0.999);
  Eigen::MatrixXd P(p, 3);
  for (long long i = 0; i < p; ++i) P.row(i) << n.x() * uni(rng), n.y() * uni(rng), n.z() * uni(rng);
  for (auto _ : st) {
    mbi::interp::Embedding emb = mbi::interp::embed(U, T, P);
    benchmark::DoNotOptimize(emb.bary.data());
  }
  st.counters["tets"] = static_cast<double>(T.rows());
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations()) * p);
}

}  // namespace

BENCHMARK(BM_Embed)->ArgNames({"points", "tets"})
    ->Args({mbi::bench::quick() ? 100000 : 1000000, 450})
    ->Args({mbi::bench::quick() ? 100000 : 1000000, 5000})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(mbi::bench::min_time(0.5));
