// What an application does with mbi, beside the isolated rows of the other files (each stage
// alone in its own loop): a frame loop of solve, Bezier points and evaluation interleaved; the
// first solve right after a precompute; each stage after a millisecond of the application's own
// work, quiet and with one core taken by another thread of the process, by another process, or
// by numpy-like BLAS calls of another thread (the loads of bench/harness/loads.hpp); two caller
// threads with objects of their own at once. scripts/bench_report.py shows them beside the
// isolated rows; bench/harness measures the same through the installed library.
//
//   build/release/mbi-bench --benchmark_filter=BM_App
#include "bench_common.hpp"
#include "harness/loads.hpp"

#include <benchmark/benchmark.h>

#include <mbi/base/timer.hpp>
#include <mbi/generate/procedural.hpp>

#include <algorithm>
#include <fstream>
#include <string>
#include <vector>

namespace {

using mbi::bench::Cage;
using mbi::bench::Cloud;
using mbi::interp::BezierPoints;
using mbi::interp::FastEvaluator;
using mbi::interp::ModifiedBI;
using mbi::interp::RowMatrixXf;
using mbi::interp::VertexMatrices;

long long app_points() { return mbi::bench::quick() ? 35000 : 1000000; }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// About `ms` of the application's own work on the calling thread (arithmetic): between two calls
// into mbi, when pool threads that spin would hold the other core.
void app_work(double ms) {
  const auto t0 = mbi::Clock::now();
  double x = 1.0;
  while (mbi::ms_since(t0) < ms)
    for (int i = 0; i < 1000; ++i) x = x * 1.0000001 + 1e-9;
  benchmark::DoNotOptimize(x);
}

// 16 poses of the 448-vertex box cage, twisted a little more each frame
const std::vector<Eigen::MatrixXd>& poses() {
  static const std::vector<Eigen::MatrixXd> X = [] {
    const Cage& c = mbi::bench::box_cage(450);
    std::vector<Eigen::MatrixXd> out;
    for (int f = 0; f < 16; ++f)
      out.push_back(mbi::generate::twist_bend(c.U, 3.5, 3.5, 0, 6, 1.2 * (0.5 + f / 32.0), 0.1));
    return out;
  }();
  return X;
}

// The frame loop: solve + Bezier points + float evaluation of the points (all threads), the
// phases interleaved as an application runs them; counters: each phase alone in its own loop of
// 16 (medians), and each phase's mean inside the frame loop.
void BM_AppFrame(benchmark::State& st) {
  const Cage& cage = mbi::bench::box_cage(450);
  const Cloud& cloud = mbi::bench::cloud(450, app_points());
  const ModifiedBI solver(cage.U, cage.T);
  FastEvaluator fast(cloud.emb);
  const auto& X = poses();
  RowMatrixXf pos;
  VertexMatrices M = solver.solve(X[0]);
  BezierPoints B = solver.bezier(X[0], M);
  fast.evaluate(B, pos);
  std::vector<double> s, b, e;
  for (int f = 0; f < 16; ++f) {
    const auto t0 = mbi::Clock::now();
    M = solver.solve(X[f]);
    s.push_back(mbi::ms_since(t0));
  }
  for (int f = 0; f < 16; ++f) {
    const auto t0 = mbi::Clock::now();
    B = solver.bezier(X[f], M);
    b.push_back(mbi::ms_since(t0));
  }
  for (int f = 0; f < 16; ++f) {
    const auto t0 = mbi::Clock::now();
    fast.evaluate(B, pos);
    e.push_back(mbi::ms_since(t0));
  }
  double ts = 0, tb = 0, te = 0;
  int f = 0;
  for (auto _ : st) {
    const auto t0 = mbi::Clock::now();
    M = solver.solve(X[f]);
    const auto t1 = mbi::Clock::now();
    B = solver.bezier(X[f], M);
    const auto t2 = mbi::Clock::now();
    fast.evaluate(B, pos);
    ts += std::chrono::duration<double, std::milli>(t1 - t0).count();
    tb += std::chrono::duration<double, std::milli>(t2 - t1).count();
    te += mbi::ms_since(t2);
    f = (f + 1) % 16;
  }
  const double n = static_cast<double>(st.iterations());
  st.counters["solve_alone_ms"] = median(s);
  st.counters["bezier_alone_ms"] = median(b);
  st.counters["evaluate_alone_ms"] = median(e);
  st.counters["sum_alone_ms"] = median(s) + median(b) + median(e);
  st.counters["solve_ms"] = ts / n;
  st.counters["bezier_ms"] = tb / n;
  st.counters["evaluate_ms"] = te / n;
  st.counters["points"] = static_cast<double>(app_points());
}
BENCHMARK(BM_AppFrame)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(mbi::bench::min_time(0.5));

// The first solve right after a precompute at 1,331 control vertices, in a process that has just
// evaluated the points (its threads ran a moment ago): the iteration's time is that solve;
// counters: the median of the 10 solves after it, and the precompute.
void BM_AppFirstSolve(benchmark::State& st) {
  const Cage& cage = mbi::bench::box_cage(450);
  const Cloud& cloud = mbi::bench::cloud(450, app_points());
  FastEvaluator fast(cloud.emb);
  RowMatrixXf pos;
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  mbi::generate::box_tets(Eigen::Vector3d::Zero(), Eigen::Vector3d(10, 10, 10), Eigen::Vector3i(10, 10, 10), U, T);
  const Eigen::MatrixXd X = mbi::generate::twist_bend(U, 5, 5, 0, 10, 1.2, 0.1);
  std::vector<double> after, pre;
  for (auto _ : st) {
    for (int k = 0; k < 3; ++k) fast.evaluate(cage.bezier_mbi, pos);
    auto t0 = mbi::Clock::now();
    const ModifiedBI solver(U, T);
    pre.push_back(mbi::ms_since(t0));
    t0 = mbi::Clock::now();
    VertexMatrices M = solver.solve(X);
    st.SetIterationTime(mbi::ms_since(t0) / 1e3);
    std::vector<double> rest;
    for (int k = 0; k < 10; ++k) {
      const auto t1 = mbi::Clock::now();
      M = solver.solve(X);
      rest.push_back(mbi::ms_since(t1));
    }
    after.push_back(median(rest));
  }
  st.counters["after_ms"] = median(after);
  st.counters["precompute_ms"] = median(pre);
}
BENCHMARK(BM_AppFirstSolve)->Iterations(5)->UseManualTime()->Unit(benchmark::kMillisecond);

// A stage after 1 ms of the application's own work, quiet or beside a load (the iteration's time
// is the stage's). Arguments: stage (0 precompute at 448, 1 precompute at 1,331, 2 solve at 448
// (dense operator), 3 solve at 1,331 (sparse sweeps), 4 evaluation of the points (float, all
// threads), 5 the whole frame), load (0 none, 1 a thread of this process, 2 another process, 3
// numpy-like BLAS calls of another thread: harness::Load).
void BM_AppLoaded(benchmark::State& st) {
  const int stage = static_cast<int>(st.range(0));
  const auto load = static_cast<harness::Load>(st.range(1));
  if (!harness::available(load)) {
    st.SkipWithError("this load is not available here (no libblas.so.3)");
    return;
  }
  const Cage& c448 = mbi::bench::box_cage(450);
  const Cloud& cloud = mbi::bench::cloud(450, app_points());
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  mbi::generate::box_tets(Eigen::Vector3d::Zero(), Eigen::Vector3d(10, 10, 10), Eigen::Vector3i(10, 10, 10), U, T);
  const Eigen::MatrixXd X1331 = mbi::generate::twist_bend(U, 5, 5, 0, 10, 1.2, 0.1);
  const ModifiedBI s448(c448.U, c448.T);
  const ModifiedBI s1331(U, T);
  FastEvaluator fast(cloud.emb);
  RowMatrixXf pos;
  VertexMatrices M = s448.solve(c448.X);
  BezierPoints B = s448.bezier(c448.X, M);
  fast.evaluate(B, pos);
  const harness::LoadGuard guard(load);
  for (auto _ : st) {
    app_work(1.0);
    const auto t0 = mbi::Clock::now();
    switch (stage) {
      case 0: benchmark::DoNotOptimize(ModifiedBI(c448.U, c448.T).beta()); break;
      case 1: benchmark::DoNotOptimize(ModifiedBI(U, T).beta()); break;
      case 2: M = s448.solve(c448.X); break;
      case 3: benchmark::DoNotOptimize(s1331.solve(X1331).data()); break;
      case 4: fast.evaluate(B, pos); break;
      default:
        M = s448.solve(c448.X);
        B = s448.bezier(c448.X, M);
        fast.evaluate(B, pos);
    }
    st.SetIterationTime(mbi::ms_since(t0) / 1e3);
  }
  st.SetLabel(harness::name(load));
}

// iterations: the precomputes 5 (quick: 2), the rest 40 (quick: 5)
[[maybe_unused]] const bool loaded_registered = [] {
  for (bool precompute : {true, false}) {
    auto* b = benchmark::RegisterBenchmark("BM_AppLoaded", BM_AppLoaded);
    b->ArgNames({"stage", "load"});
    for (int stage = precompute ? 0 : 2; stage <= (precompute ? 1 : 5); ++stage)
      for (int load = 0; load <= 3; ++load)
        if (!mbi::bench::quick() || load <= 1) b->Args({stage, load});
    b->Iterations(precompute ? (mbi::bench::quick() ? 2 : 5) : (mbi::bench::quick() ? 5 : 40));
    b->UseManualTime()->Unit(benchmark::kMillisecond);
  }
  return true;
}();

// Threads of this process now (Linux; -1 elsewhere).
int process_threads() {
  std::ifstream f("/proc/self/status");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8));
  return -1;
}

// Frames (solve + Bezier + evaluation, 448 control vertices) on 1 or 2 caller threads at once,
// each with a precompute and an evaluator of its own (two objects, as two Python threads hold);
// counter: the threads of the process meanwhile (the benchmark's own included).
void BM_AppCallers(benchmark::State& st) {
  const Cage& cage = mbi::bench::box_cage(450);
  const Cloud& cloud = mbi::bench::cloud(450, app_points());
  const ModifiedBI solver(cage.U, cage.T);
  FastEvaluator fast(cloud.emb);
  RowMatrixXf pos;
  int most = 0;
  for (auto _ : st) {
    const VertexMatrices M = solver.solve(cage.X);
    fast.evaluate(solver.bezier(cage.X, M), pos);
    most = std::max(most, process_threads());
  }
  if (st.thread_index() == 0) st.counters["process_threads"] = most;
}
BENCHMARK(BM_AppCallers)->Threads(1)->Threads(2)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time(0.5));

}  // namespace
