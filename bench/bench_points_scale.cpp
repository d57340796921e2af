// Dense models of 1M to 10M points in control meshes up to 511K tetrahedra: embedding them, and
// evaluating them a frame, against the triad time of the bytes the evaluation must move.
//
//   build/release/mbi-bench --benchmark_filter='BM_EmbedScale|BM_EvalScale|BM_Triad'
//
// Control meshes: unit boxes of n^3 cells, 6 tetrahedra a cell (n = 10: 6,000; n = 44: 511,104).
// Points: uniformly random inside, in two orders: `random` (each point anywhere: the worst case
// for the cache; over 16 MiB of element terms the evaluator sorts its records by element and
// scatters the results to the points' rows) and `by element` (sorted by the element they lie
// in, as a model whose vertex order follows its surface mostly is). Evaluation: the float kernel
// (interp::FastEvaluator) with BI's Bezier points of a twisted pose, bytes counted as BM_Eval
// counts them (bench_throughput.cpp); records in element order take the fused pass (the element
// terms computed block by block next to their records), and fused:0 rows the table's pass for
// comparison. Full run only (MBI_BENCH_QUICK skips the 10M rows).
#include "bench_common.hpp"

#include <mbi/interp/fast_evaluate.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <memory>
#include <numeric>

namespace {

struct Grid {
  Eigen::MatrixXd U, X;
  Eigen::MatrixXi T;
};

const Grid& grid(int n) {
  static std::map<int, std::unique_ptr<Grid>> cache;
  auto& slot = cache[n];
  if (!slot) {
    slot = std::make_unique<Grid>();
    const Eigen::Vector3i c(n, n, n);
    mbi::generate::box_tets(Eigen::Vector3d::Zero(), c.cast<double>(), c, slot->U, slot->T);
    slot->X = mbi::generate::twist_bend(slot->U, 0.5 * n, 0.5 * n, 0, n, 1.2, 0.1);
  }
  return *slot;
}

Eigen::MatrixXd random_points(int n, long long p) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(0.001 * n, 0.999 * n);
  Eigen::MatrixXd P(p, 3);
  for (long long i = 0; i < p; ++i) P.row(i) << uni(rng), uni(rng), uni(rng);
  return P;
}

// The embedding with its points sorted by element (stable: ties keep their order).
mbi::interp::Embedding by_element(const mbi::interp::Embedding& e) {
  std::vector<Eigen::Index> order(static_cast<size_t>(e.size()));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return e.element(a) < e.element(b); });
  mbi::interp::Embedding s = e;
  for (size_t k = 0; k < order.size(); ++k) {
    s.element(static_cast<Eigen::Index>(k)) = e.element(order[k]);
    s.bary.row(static_cast<Eigen::Index>(k)) = e.bary.row(order[k]);
  }
  return s;
}

// Arguments: points, cells across (n).
void BM_EmbedScale(benchmark::State& st) {
  const long long p = st.range(0);
  const int n = static_cast<int>(st.range(1));
  const Grid& g = grid(n);
  const Eigen::MatrixXd P = random_points(n, p);
  for (auto _ : st) {
    mbi::interp::Embedding emb = mbi::interp::embed(g.U, g.T, P);
    benchmark::DoNotOptimize(emb.bary.data());
  }
  st.counters["tets"] = static_cast<double>(g.T.rows());
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations()) * p);
}

// Arguments: points, cells across (n), order (0 = random, 1 = by element), fused (0: the element
// terms written to a table each call, then read per point, even where the evaluator would fuse
// the two: the comparison).
void BM_EvalScale(benchmark::State& st) {
  const long long p = st.range(0);
  const int n = static_cast<int>(st.range(1));
  const Grid& g = grid(n);
  mbi::interp::Embedding emb = mbi::interp::embed(g.U, g.T, random_points(n, p));
  if (st.range(2) == 1) emb = by_element(emb);
  mbi::interp::FastEvaluator fe(emb);
  fe.set_fused_terms(st.range(3) == 1);
  emb = mbi::interp::Embedding{};  // the evaluator holds its own packed copy
  const mbi::interp::BezierPoints B = mbi::interp::bezier_bi(g.X, g.T);
  mbi::interp::RowMatrixXf pos(p, 3);
  fe.evaluate(B, pos);  // output touched before the timing
  for (auto _ : st) {
    fe.evaluate(B, pos);
    benchmark::DoNotOptimize(pos.data());
    benchmark::ClobberMemory();
  }
  const double bytes = static_cast<double>(p) * 28.0 + static_cast<double>(g.T.rows()) * 10 * 3 * 8.0;
  st.counters["tets"] = static_cast<double>(g.T.rows());
  st.counters["sorted"] = fe.sorted_by_element() ? 1 : 0;  // the evaluator's records a permutation of the points
  st.counters["fused"] = fe.fused_terms() ? 1 : 0;
  st.counters["bytes_per_eval"] = bytes;
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations()) * p);
  st.SetBytesProcessed(static_cast<int64_t>(static_cast<double>(st.iterations()) * bytes));
}

void embed_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"points", "cells"});
  if (mbi::bench::quick()) return void(b->Args({100000, 10}));
  for (long long p : {1000000LL, 10000000LL})
    for (int n : {10, 44}) b->Args({p, n});
}

// fused:0 only where the evaluator fuses (records in element order: by element, or sorted by it
// over 44^3 cells)
void eval_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"points", "cells", "by_element", "fused"});
  if (mbi::bench::quick()) return void(b->Args({100000, 10, 0, 1}));
  for (long long p : {1000000LL, 10000000LL})
    for (int n : {10, 44})
      for (int order : {0, 1})
        for (int fused : {1, 0})
          if (fused == 1 || order == 1 || n == 44) b->Args({p, n, order, fused});
}

BENCHMARK(BM_EmbedScale)->Apply(embed_args)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_EvalScale)->Apply(eval_args)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time(0.5));

}  // namespace
