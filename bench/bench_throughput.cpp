// Evaluation throughput of the embedded points: our kernel (interp::evaluate) against peers and
// against the machine's memory bandwidth, in one run (scripts/bench.sh turns it into the report).
//
//   build/release/mbi-bench --benchmark_filter='BM_Eval|BM_Peer|BM_Triad'
//
// Points: uniformly random in a box control mesh of 100 or 448 vertices (bench_common.hpp),
// twisted and bent. Every benchmark sets bytes_per_second from the bytes it must read and write
// (STREAM convention: each byte read or written once, write-allocate traffic not counted):
//
//   BM_Eval (our kernel)   float: the compact kernel interp::FastEvaluator, per point the packed
//                          record 16 B (element id 4 B + 3 float coordinates) + position out
//                          3 x 4 B = 28 B; with normals also rest normal in 3 x 4 B + normal out
//                          3 x 4 B (52 B); per call the Bezier points (m x 10 x 3 doubles).
//                          double: interp::evaluate<double> (the exact path), per point element
//                          id 4 B + 4 barycentric coordinates 4 x 8 B (the Embedding's doubles) +
//                          position out 3 x 8 B; with normals also rest normal in + normal out
//                          3 x 8 B each; per call the Bezier points and, with normals, the basis
//                          gradients (m x 4 x 3 doubles).
//   BM_PeerEigenSparse     per point: 4 values 4 x 8 B + 4 column indices 4 x 4 B + row start
//                          4 B + output 3 x 8 B; per call the n x 3 control positions.
//   BM_PeerVegaLoop        per point: 4 vertex indices 4 x 4 B + 4 weights 4 x 8 B + output
//                          3 x 8 B; per call the n x 3 control positions.
//   BM_PeerMbiFormula      per point: element id 4 B + 4 coordinates 4 x 8 B + rest point
//                          3 x 8 B + output 3 x 8 B; per call x_i, u_i, M_i (15 doubles a vertex).
//   BM_EvalKernels         BM_Eval's float rows at 1M points with each kernel the CPU runs
//                          (interp::Simd: AVX-512, AVX2, portable); BM_Eval runs the one picked
//                          at run time (its label names it).
//   BM_Triad               a[i] = b[i] + s c[i]: 3 x 8 B per element (as STREAM counts it).
#include "bench_common.hpp"

#include <mbi/interp/threads.hpp>

#include <benchmark/benchmark.h>

#include <Eigen/SparseCore>

#include <algorithm>
#include <array>
#include <string>
#include <thread>

namespace {

using mbi::bench::Cage;
using mbi::bench::Cloud;
using mbi::interp::BezierPoints;

// the library's thread count (mbi/interp/threads.hpp): what "all threads" runs on
int all_threads() { return mbi::interp::threads(); }

/// Bytes one evaluation must read and write (see the file comment).
double eval_bytes(long long p, long long elements, bool dbl, bool normals) {
  const double per_point = dbl ? 4 + 4 * 8 + 3 * 8 + (normals ? 6 * 8 : 0) : 16 + 12 + (normals ? 24 : 0);
  const double per_call = elements * 10 * 3 * 8.0 + (dbl && normals ? elements * 4 * 3 * 8.0 : 0.0);
  return static_cast<double>(p) * per_point + per_call;
}

// Every loop below writes into outputs allocated and touched before the timing: first touch of
// fresh memory is part of no frame (on this project's VM it cost 0.3 s for 4M double points, so a
// benchmark whose one iteration allocated its output measured mostly page faults).
void eval_loop_double(benchmark::State& st, const BezierPoints& B, const Cloud& c, bool normals, int threads) {
  Eigen::MatrixXd pos, nout;
  if (normals) mbi::interp::evaluate<double>(B, c.emb, c.normals, pos, nout, threads);  // sizes the outputs
  else mbi::interp::evaluate<double>(B, c.emb, pos, threads);
  for (auto _ : st) {
    if (normals) mbi::interp::evaluate<double>(B, c.emb, c.normals, pos, nout, threads);
    else mbi::interp::evaluate<double>(B, c.emb, pos, threads);
    benchmark::DoNotOptimize(pos.data());
    benchmark::ClobberMemory();
  }
}

void eval_loop_float(benchmark::State& st, const BezierPoints& B, const Cloud& c, bool normals, int threads,
                     mbi::interp::Simd simd = mbi::interp::Simd::Auto) {
  mbi::interp::FastEvaluator fe(c.emb, threads, simd);
  st.SetLabel(mbi::interp::FastEvaluator::name(fe.simd()));  // the kernels that ran
  if (normals) fe.set_rest_normals(c.normals);
  mbi::interp::RowMatrixXf pos, nout;
  if (normals) fe.evaluate(B, pos, nout);  // first call sizes the outputs
  else fe.evaluate(B, pos);
  for (auto _ : st) {
    if (normals) fe.evaluate(B, pos, nout);
    else fe.evaluate(B, pos);
    benchmark::DoNotOptimize(pos.data());
    benchmark::ClobberMemory();
  }
  st.counters["threads_used"] = fe.threads();
}

// Arguments: points, control (100 / 450), mbi (0 = BI, 1 = modified-BI), threads (0 = all),
// double (0 = float), normals (0 = positions only).
void BM_Eval(benchmark::State& st) {
  const long long p = st.range(0);
  const int control = static_cast<int>(st.range(1));
  const bool modified = st.range(2) != 0;
  const int threads = static_cast<int>(st.range(3));
  const bool dbl = st.range(4) != 0;
  const bool normals = st.range(5) != 0;
  const Cage& cage = mbi::bench::box_cage(control);
  const Cloud& c = mbi::bench::cloud(control, p);
  const BezierPoints& B = modified ? cage.bezier_mbi : cage.bezier_bi;
  if (dbl) eval_loop_double(st, B, c, normals, threads);
  else eval_loop_float(st, B, c, normals, threads);
  const double bytes = eval_bytes(p, cage.T.rows(), dbl, normals);
  st.counters["bytes_per_eval"] = bytes;
  st.counters["threads"] = threads > 0 ? threads : all_threads();
  st.counters["control"] = static_cast<double>(cage.U.rows());
  st.counters["elements"] = static_cast<double>(cage.T.rows());
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations()) * p);
  st.SetBytesProcessed(static_cast<int64_t>(static_cast<double>(st.iterations()) * bytes));
}

void eval_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"points", "control", "mbi", "threads", "double", "normals"});
  for (long long p : mbi::bench::point_counts())
    for (int control : {100, 450})
      for (int mbi : {0, 1})
        for (int threads : {1, 0})
          for (int dbl : {0, 1})
            for (int normals : {0, 1}) b->Args({p, control, mbi, threads, dbl, normals});
}
BENCHMARK(BM_Eval)->Apply(eval_args)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time());

// The float kernels side by side (interp::Simd): 1M points (quick: 35K), modified-BI, 448 control
// vertices. Arguments: simd (1 = AVX-512, 2 = AVX2, 3 = portable), threads (0 = all), normals.
// A kernel this CPU cannot run is skipped, saying so.
void BM_EvalKernels(benchmark::State& st) {
  using mbi::interp::FastEvaluator;
  using mbi::interp::Simd;
  const long long p = mbi::bench::quick() ? 35000 : 1000000;
  const Simd simd = st.range(0) == 1 ? Simd::Avx512 : st.range(0) == 2 ? Simd::Avx2 : Simd::Portable;
  const int threads = static_cast<int>(st.range(1));
  const bool normals = st.range(2) != 0;
  if (!FastEvaluator::supported(simd)) {
    st.SkipWithError((std::string("this CPU cannot run the ") + FastEvaluator::name(simd) + " kernels").c_str());
    return;
  }
  const Cage& cage = mbi::bench::box_cage(450);
  const Cloud& c = mbi::bench::cloud(450, p);
  eval_loop_float(st, cage.bezier_mbi, c, normals, threads, simd);
  const double bytes = eval_bytes(p, cage.T.rows(), false, normals);
  st.counters["points"] = static_cast<double>(p);
  st.counters["bytes_per_eval"] = bytes;
  st.counters["threads"] = threads > 0 ? threads : all_threads();
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations()) * p);
  st.SetBytesProcessed(static_cast<int64_t>(static_cast<double>(st.iterations()) * bytes));
}
BENCHMARK(BM_EvalKernels)->ArgNames({"simd", "threads", "normals"})
    ->ArgsProduct({{1, 2, 3}, {1, 0}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time());

// ------------------------------------------------------------------------------------- peers

/// The reference result of a peer: our kernel in double (BI or modified-BI).
Eigen::MatrixXd reference(const Cage& cage, const Cloud& c, bool modified) {
  Eigen::MatrixXd pos;
  mbi::interp::evaluate<double>(modified ? cage.bezier_mbi : cage.bezier_bi, c.emb, pos, 0);
  return pos;
}

/// Skips the benchmark unless `got` (p x 3, any layout) agrees with our kernel.
template <typename Matrix>
bool agrees(benchmark::State& st, const Matrix& got, const Eigen::MatrixXd& want) {
  const double err = (got - want).cwiseAbs().maxCoeff();
  st.counters["max_diff_vs_kernel"] = err;
  if (err <= 1e-9 * (1.0 + want.cwiseAbs().maxCoeff())) return true;
  st.SkipWithError("the peer's result differs from our kernel's");
  return false;
}

void peer_counters(benchmark::State& st, long long p, double bytes) {
  st.counters["bytes_per_eval"] = bytes;
  st.counters["threads"] = 1;
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations()) * p);
  st.SetBytesProcessed(static_cast<int64_t>(static_cast<double>(st.iterations()) * bytes));
}

// BI as a sparse matrix product: W (p x n, RowMajor, 4 nonzeros a row) times X (n x 3,
// RowMajor). Eigen without OpenMP: 1 thread.
void BM_PeerEigenSparse(benchmark::State& st) {
  const long long p = st.range(0);
  const Cage& cage = mbi::bench::box_cage(static_cast<int>(st.range(1)));
  const Cloud& c = mbi::bench::cloud(static_cast<int>(st.range(1)), p);
  const Eigen::Index n = cage.U.rows();
  Eigen::SparseMatrix<double, Eigen::RowMajor> W(p, n);
  W.resizeNonZeros(4 * p);
  for (long long i = 0; i < p; ++i) {
    const int e = c.emb.element(i);
    std::array<std::pair<int, double>, 4> row;
    for (int k = 0; k < 4; ++k) row[k] = {cage.T(e, k), c.emb.bary(i, k)};
    std::sort(row.begin(), row.end());
    W.outerIndexPtr()[i] = static_cast<int>(4 * i);
    for (int k = 0; k < 4; ++k) {
      W.innerIndexPtr()[4 * i + k] = row[k].first;
      W.valuePtr()[4 * i + k] = row[k].second;
    }
  }
  W.outerIndexPtr()[p] = static_cast<int>(4 * p);
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> X = cage.X;
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> Y = Eigen::MatrixXd::Zero(p, 3);
  for (auto _ : st) {
    Y.noalias() = W * X;
    benchmark::DoNotOptimize(Y.data());
    benchmark::ClobberMemory();
  }
  if (!agrees(st, Y, reference(cage, c, false))) return;
  peer_counters(st, p, static_cast<double>(p) * (4 * 8 + 4 * 4 + 4 + 3 * 8) + n * 3 * 8.0);
}

// The plain per-point BI loop of VegaFEM's VolumetricMesh::interpolate: 4 vertex indices and
// 4 weights stored per point, double, 1 thread.
void BM_PeerVegaLoop(benchmark::State& st) {
  const long long p = st.range(0);
  const Cage& cage = mbi::bench::box_cage(static_cast<int>(st.range(1)));
  const Cloud& c = mbi::bench::cloud(static_cast<int>(st.range(1)), p);
  const Eigen::Index n = cage.U.rows();
  std::vector<int> vertices(4 * p);
  std::vector<double> weights(4 * p), mesh(3 * n), dest(3 * p);
  for (long long i = 0; i < p; ++i)
    for (int k = 0; k < 4; ++k) {
      vertices[4 * i + k] = cage.T(c.emb.element(i), k);
      weights[4 * i + k] = c.emb.bary(i, k);
    }
  for (Eigen::Index v = 0; v < n; ++v)
    for (int a = 0; a < 3; ++a) mesh[3 * v + a] = cage.X(v, a);
  for (auto _ : st) {
    const int* vert = vertices.data();
    const double* w = weights.data();
    const double* x = mesh.data();
    double* out = dest.data();
    for (long long i = 0; i < p; ++i) {
      double d0 = 0, d1 = 0, d2 = 0;
      for (int j = 0; j < 4; ++j) {
        const double* xv = x + 3 * static_cast<long long>(vert[4 * i + j]);
        const double wj = w[4 * i + j];
        d0 += wj * xv[0];
        d1 += wj * xv[1];
        d2 += wj * xv[2];
      }
      out[3 * i + 0] = d0;
      out[3 * i + 1] = d1;
      out[3 * i + 2] = d2;
    }
    benchmark::DoNotOptimize(dest.data());
    benchmark::ClobberMemory();
  }
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> got(dest.data(), p, 3);
  if (!agrees(st, got, reference(cage, c, false))) return;
  peer_counters(st, p, static_cast<double>(p) * (4 * 4 + 4 * 8 + 3 * 8) + n * 3 * 8.0);
}

// Modified-BI straight from its definition, x(u) = sum_i phi_i (x_i + M_i (u - u_i)), per point,
// double, 1 thread.
void BM_PeerMbiFormula(benchmark::State& st) {
  const long long p = st.range(0);
  const Cage& cage = mbi::bench::box_cage(static_cast<int>(st.range(1)));
  const Cloud& c = mbi::bench::cloud(static_cast<int>(st.range(1)), p);
  const Eigen::Index n = cage.U.rows();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(p, 3);
  for (auto _ : st) {
    for (long long i = 0; i < p; ++i) {
      const int e = c.emb.element(i);
      const Eigen::Vector3d u = c.P.row(i).transpose();
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) {
        const int v = cage.T(e, k);
        const Eigen::Matrix3d Mi = cage.M.block<3, 3>(3 * v, 0);
        const Eigen::Vector3d du = u - cage.U.row(v).transpose();
        x += c.emb.bary(i, k) * (cage.X.row(v).transpose() + Mi * du);
      }
      out.row(i) = x.transpose();
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  if (!agrees(st, out, reference(cage, c, true))) return;
  peer_counters(st, p, static_cast<double>(p) * (4 + 4 * 8 + 3 * 8 + 3 * 8) + n * 15 * 8.0);
}

void peer_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"points", "control"});
  for (long long p : mbi::bench::point_counts())
    for (int control : {100, 450}) b->Args({p, control});
}
BENCHMARK(BM_PeerEigenSparse)->Apply(peer_args)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time());
BENCHMARK(BM_PeerVegaLoop)->Apply(peer_args)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time());
BENCHMARK(BM_PeerMbiFormula)->Apply(peer_args)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time());

// ------------------------------------------------------------------------------------- limit

// STREAM-style triad a = b + s c over arrays far larger than the caches (3 x 128 MB; 3 x 32 MB
// in quick mode), on 1 thread or all (argument 0), each thread on its own contiguous part.
void BM_Triad(benchmark::State& st) {
  const int threads = st.range(0) > 0 ? static_cast<int>(st.range(0)) : all_threads();
  const long long n = mbi::bench::quick() ? (1LL << 22) : (1LL << 24);
  std::vector<double> a(n), b(n, 1.0), c(n, 2.0);
  const double s = 3.0;
  auto part = [&](int t) {
    const long long lo = n * t / threads, hi = n * (t + 1) / threads;
    double* pa = a.data();
    const double* pb = b.data();
    const double* pc = c.data();
    for (long long i = lo; i < hi; ++i) pa[i] = pb[i] + s * pc[i];
  };
  for (auto _ : st) {
    if (threads == 1) {
      part(0);
    } else {
      std::vector<std::thread> pool;
      for (int t = 0; t < threads; ++t) pool.emplace_back(part, t);
      for (auto& th : pool) th.join();
    }
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  st.counters["threads"] = threads;
  st.counters["bytes_per_eval"] = 24.0 * n;
  st.SetBytesProcessed(static_cast<int64_t>(st.iterations()) * 24 * n);
}
BENCHMARK(BM_Triad)->ArgName("threads")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time(0.5));

}  // namespace
