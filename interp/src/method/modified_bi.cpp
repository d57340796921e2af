// Modified-BI precompute (assembly, beta, gauge, factorisation) and per-frame solve.
#include <mbi/interp/modified_bi.hpp>
#include <mbi/interp/memory.hpp>

#include "method/detail.hpp"
#include "linalg/factor.hpp"
#include "linalg/iterative.hpp"
#include "runtime/cpu.hpp"
#include "runtime/threads.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <numeric>
#include <string>
#include <thread>
#include <vector>

namespace mbi::interp {

using SpMat = Eigen::SparseMatrix<double>;
using Triplets = std::vector<Eigen::Triplet<double>>;

namespace {
// Solve path threshold: the dense operator is used when (unknowns per component) x n is at most
// this many entries. Measured with mbi-bench (BM_Solve*, see bench/bench_interp.cpp).
constexpr long long kDenseOperatorMaxEntries = 1LL << 21;

// SolvePath::Automatic takes the iterative path when the precompute's estimated peak (memory.hpp)
// exceeds the memory the run may take (options.max_memory, or what memory_limit finds). The
// estimate (a symbolic analysis) runs only where a rough upper bound, 100 MB (n / 1000)^1.5
// (above the measured peaks from 1,000 to 20,000 vertices), exceeds half of it, so smaller
// meshes pay nothing for the check.
bool factor_would_not_fit(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                          const Options& options) {
  std::string name;
  const double available = memory_limit(options.max_memory, name);
  if (!(available > 0)) return false;
  if (100e6 * std::pow(static_cast<double>(U.rows()) / 1000.0, 1.5) <= 0.5 * available) return false;
  return estimate_memory(U, T, 0, options).peak_bytes > available;
}

// max over elements of h^2 / sqrt(|t|), h the element's longest edge: a change dm of M moves x(u)
// inside the control mesh by at most this / (4 sqrt(alpha)) times dm's A-norm (fact 19).
double position_scale(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T) {
  const int d = static_cast<int>(U.cols());
  double s = 0;
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    double h = 0;
    Eigen::MatrixXd E(d, d);
    for (int k = 0; k < d; ++k) E.col(k) = (U.row(T(e, k + 1)) - U.row(T(e, 0))).transpose();
    for (Eigen::Index a = 0; a <= d; ++a)
      for (Eigen::Index b = a + 1; b <= d; ++b) h = std::max(h, (U.row(T(e, a)) - U.row(T(e, b))).norm());
    const double volume = std::abs(E.determinant()) / (d == 3 ? 6.0 : 2.0);
    s = std::max(s, h * h / std::sqrt(volume));
  }
  return s;
}

// The rows (and, with cols, the columns) of H that the maps keep (map[k] >= 0: the new index,
// increasing in k, the kept columns numbered 0..ncols-1 without gaps), in one pass over H: what
// R H R^T (or R H) gives with R the 0/1 selection, without forming the products. H must be
// compressed (sorted rows in each column), as assembled.
SpMat restrict_to(const SpMat& H, const std::vector<int>& rows, int nrows, const std::vector<int>* cols, int ncols) {
  eigen_assert(H.isCompressed());
  SpMat out(nrows, ncols);
  out.reserve(H.nonZeros());
  for (int j = 0; j < H.outerSize(); ++j) {
    const int c = cols ? (*cols)[static_cast<size_t>(j)] : j;
    if (c < 0) continue;
    out.startVec(c);
    for (SpMat::InnerIterator it(H, j); it; ++it) {
      const int r = rows[static_cast<size_t>(it.row())];
      if (r >= 0) out.insertBack(r, c) = it.value();
    }
  }
  out.finalize();
  return out;
}
}  // namespace

namespace detail {

std::vector<char> gauge_pins(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T,
                             const std::vector<char>& free_vertex, int& null_dim) {
  const int d = static_cast<int>(U.cols());
  const int n = static_cast<int>(U.rows());
  const int m = static_cast<int>(T.rows());
  const int k = d + d * (d - 1) / 2;
  null_dim = 0;
  std::vector<char> pinned(static_cast<size_t>(d) * n, 0);
  // face-connected components of elements (union-find)
  std::vector<int> parent(m);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  const Eigen::MatrixXi F = interior_faces(T);
  for (int f = 0; f < F.rows(); ++f) parent[find(F(f, d))] = find(F(f, d + 1));
  std::vector<int> comp_of_vertex(n, -1);
  std::vector<std::vector<int>> comps(m);
  for (int e = 0; e < m; ++e) {
    const int c = find(e);
    for (int j = 0; j <= d; ++j) {
      const int v = T(e, j);
      if (comp_of_vertex[v] == -1) {
        comp_of_vertex[v] = c;
        comps[c].push_back(v);
      } else if (comp_of_vertex[v] != c) {
        throw Error("vertex " + std::to_string(v) + " (of element " + std::to_string(e) +
                    ") joins two parts of the control mesh that share no face; split the mesh "
                    "into separate objects");
      }
    }
  }
  for (const auto& verts : comps) {
    if (verts.empty()) continue;
    // null vectors m_i = t + S c_i (c_i: centred, scaled rest positions), rows (vertex, r)
    Eigen::RowVectorXd centre = Eigen::RowVectorXd::Zero(d);
    for (int v : verts) centre += U.row(v);
    centre /= static_cast<double>(verts.size());
    double scale = 0;
    for (int v : verts) scale = std::max(scale, (U.row(v) - centre).norm());
    if (!(scale > 0)) scale = 1;
    const int nc = static_cast<int>(verts.size());
    Eigen::MatrixXd N = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(d) * nc, k);
    for (int j = 0; j < nc; ++j) {
      const Eigen::RowVectorXd c = (U.row(verts[j]) - centre) / scale;
      for (int r = 0; r < d; ++r) N(j * d + r, r) = 1.0;
      int col = d;
      for (int p = 0; p < d; ++p)
        for (int q = p + 1; q < d; ++q, ++col) {  // S = e_p e_q^T - e_q e_p^T
          N(j * d + p, col) = c(q);
          N(j * d + q, col) = -c(p);
        }
    }
    // Null vectors that survive the fixed vertices: kernel of N restricted to fixed rows.
    std::vector<int> fixed_rows, free_rows;
    for (int j = 0; j < nc; ++j)
      for (int r = 0; r < d; ++r) (free_vertex[verts[j]] ? free_rows : fixed_rows).push_back(j * d + r);
    Eigen::MatrixXd Z = Eigen::MatrixXd::Identity(k, k);
    if (!fixed_rows.empty()) {
      Eigen::MatrixXd Nf(fixed_rows.size(), k);
      for (size_t i = 0; i < fixed_rows.size(); ++i) Nf.row(i) = N.row(fixed_rows[i]);
      Eigen::FullPivLU<Eigen::MatrixXd> lu(Nf);
      lu.setThreshold(1e-10);
      Z = lu.rank() == k ? Eigen::MatrixXd(k, 0) : Eigen::MatrixXd(lu.kernel());
    }
    const int kk = static_cast<int>(Z.cols());
    if (kk == 0 || free_rows.empty()) continue;
    Eigen::MatrixXd Nr(free_rows.size(), kk);
    {
      const Eigen::MatrixXd NZ = N * Z;
      for (size_t i = 0; i < free_rows.size(); ++i) Nr.row(i) = NZ.row(free_rows[i]);
    }
    // Pick kk unknowns on which the null vectors are best conditioned (column-pivoted QR of
    // Nr^T); pinning them to zero removes the null space without changing x(u).
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Nr.transpose());
    const Eigen::MatrixXd R = qr.matrixR().template triangularView<Eigen::Upper>();
    if (!(std::abs(R(kk - 1, kk - 1)) > 1e-8 * std::abs(R(0, 0))))
      throw Error("cannot fix the gauge of the component containing vertex " +
                  std::to_string(verts[0]) + " (its vertices are too close to collinear)");
    for (int i = 0; i < kk; ++i) {
      const int row = free_rows[qr.colsPermutation().indices()(i)];
      pinned[static_cast<size_t>(verts[row / d]) * d + row % d] = 1;
    }
    null_dim += kk;
  }
  return pinned;
}

}  // namespace detail

const std::vector<std::pair<int, int>>& bezier_edges(int d) {
  static const std::vector<std::pair<int, int>> e2{{0, 1}, {0, 2}, {1, 2}};
  static const std::vector<std::pair<int, int>> e3{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  if (d == 2) return e2;
  if (d == 3) return e3;
  throw Error("dimension must be 2 or 3, got " + std::to_string(d));
}

namespace {

// rows [a0, a1) of R (row-major, rows W doubles apart, D columns) = A X for A in CSR (outer,
// inner, val) and X with its rows `is` and its columns `ld` doubles apart; D a constant, so that
// the compiler keeps the D sums in registers.
template <int D>
void rhs_rows(const int* outer, const int* inner, const double* val, const double* x, Eigen::Index is,
              Eigen::Index ld, double* R, Eigen::Index W, long long a0, long long a1) {
  for (long long a = a0; a < a1; ++a) {
    double acc[D] = {};
    for (int p = outer[a]; p < outer[a + 1]; ++p)
      for (int c = 0; c < D; ++c) acc[c] += val[p] * x[inner[p] * is + c * ld];
    for (int c = 0; c < D; ++c) R[a * W + c] = acc[c];
  }
}

// sol (r x 3, row-major) = K (r x n, row-major) X, X given by its 3 columns xs, ys, zs (each n
// doubles; zs zero in 2D), rows [r0, r1).
void dense_rows_portable(const double* K, std::ptrdiff_t n, const double* xs, const double* ys,
                         const double* zs, double* sol, std::ptrdiff_t r0, std::ptrdiff_t r1) {
  for (std::ptrdiff_t r = r0; r < r1; ++r) {
    const double* k = K + r * n;
    double a0 = 0, a1 = 0, a2 = 0;
    for (std::ptrdiff_t j = 0; j < n; ++j) {
      a0 += k[j] * xs[j];
      a1 += k[j] * ys[j];
      a2 += k[j] * zs[j];
    }
    sol[3 * r] = a0;
    sol[3 * r + 1] = a1;
    sol[3 * r + 2] = a2;
  }
}

#ifdef MBI_INTERP_X86
__attribute__((target("avx2,fma"))) inline double hsum(__m256d v) {
  const __m128d s = _mm_add_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
  return _mm_cvtsd_f64(_mm_add_sd(s, _mm_unpackhi_pd(s, s)));
}

// Two rows of K at a time, 4 vertices a step: each load of the 3 columns serves both rows, and
// no lane is padding (3 FMAs per 4 entries of K, against one per entry with the entry broadcast).
__attribute__((target("avx2,fma"))) void dense_rows_avx2(const double* K, std::ptrdiff_t n,
                                                         const double* xs, const double* ys,
                                                         const double* zs, double* sol,
                                                         std::ptrdiff_t r0, std::ptrdiff_t r1) {
  std::ptrdiff_t r = r0;
  for (; r + 2 <= r1; r += 2) {
    const double* k0 = K + r * n;
    const double* k1 = k0 + n;
    __m256d x0 = _mm256_setzero_pd(), y0 = x0, z0 = x0, x1 = x0, y1 = x0, z1 = x0;
    std::ptrdiff_t j = 0;
    for (; j + 4 <= n; j += 4) {
      const __m256d vx = _mm256_loadu_pd(xs + j), vy = _mm256_loadu_pd(ys + j), vz = _mm256_loadu_pd(zs + j);
      const __m256d a = _mm256_loadu_pd(k0 + j), b = _mm256_loadu_pd(k1 + j);
      x0 = _mm256_fmadd_pd(a, vx, x0);
      y0 = _mm256_fmadd_pd(a, vy, y0);
      z0 = _mm256_fmadd_pd(a, vz, z0);
      x1 = _mm256_fmadd_pd(b, vx, x1);
      y1 = _mm256_fmadd_pd(b, vy, y1);
      z1 = _mm256_fmadd_pd(b, vz, z1);
    }
    double s[6] = {hsum(x0), hsum(y0), hsum(z0), hsum(x1), hsum(y1), hsum(z1)};
    for (; j < n; ++j) {
      s[0] += k0[j] * xs[j], s[1] += k0[j] * ys[j], s[2] += k0[j] * zs[j];
      s[3] += k1[j] * xs[j], s[4] += k1[j] * ys[j], s[5] += k1[j] * zs[j];
    }
    for (int c = 0; c < 6; ++c) sol[3 * r + c] = s[c];
  }
  if (r < r1) dense_rows_portable(K, n, xs, ys, zs, sol, r, r1);
}
#endif

void dense_rows(const double* K, std::ptrdiff_t n, const double* xs, const double* ys, const double* zs,
                double* sol, std::ptrdiff_t r0, std::ptrdiff_t r1) {
#ifdef MBI_INTERP_X86
  if (detail::have_avx2_fma()) return dense_rows_avx2(K, n, xs, ys, zs, sol, r0, r1);
#endif
  dense_rows_portable(K, n, xs, ys, zs, sol, r0, r1);
}

}  // namespace

bool cholmod_available() { return detail::cholmod_available(); }

struct ModifiedBI::Impl {
  int d = 3, n = 0, m = 0;
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  Options opt;
  double alpha = 0, beta = 0;
  std::vector<int> reduced;  // full m index -> reduced index, -1 when pinned to 0
  int n_red = 0;
  int null_dim = 0;
  // -beta R H_mx, by rows: the right-hand sides and the transpose. The Hessians themselves are
  // not kept (set_alpha assembles them again), so that a bound model holds little beyond the factor.
  Eigen::SparseMatrix<double, Eigen::RowMajor> rhs_op;
  detail::CholeskyFactor F;
  bool dense = false;
  // dense operator -H^-1 H_mx, row-major (n_red x n): row a holds reduced unknown a's weights
  std::vector<double> K;
  // the iterative path (fact 19): PCG in place of F, its stopping residual for the forward solve
  bool iterative = false;
  std::unique_ptr<detail::PcgSolver> pcg;
  double model_size = 0, position_scale = 0;
  // per calling thread: its last solution (n_red x d, the next solve's start) and iterations
  struct Warm {
    std::thread::id thread;
    Eigen::MatrixXd sol;
    int iterations = 0;
  };
  mutable std::mutex warm_mutex;
  mutable std::vector<Warm> warm;

  int max_iterations() const { return opt.max_iterations > 0 ? opt.max_iterations : 20000; }

  // Where PCG stops so that the positions x(u) (u in the control mesh) are within 1e-6 of the
  // model size (fact 19): |dx_c(u)| <= position_scale / (4 sqrt(alpha)) |dm_c|_A per component.
  detail::PcgSolver::Tolerance forward_tolerance() const {
    return {1e-6 * model_size / std::sqrt(static_cast<double>(d)) * 4 * std::sqrt(alpha) / position_scale, false};
  }

  Warm take_warm() const {
    std::lock_guard<std::mutex> lock(warm_mutex);
    for (Warm& w : warm)
      if (w.thread == std::this_thread::get_id()) return std::move(w);
    return {std::this_thread::get_id(), Eigen::MatrixXd::Zero(n_red, d), 0};
  }
  void keep_warm(Warm&& w) const {
    std::lock_guard<std::mutex> lock(warm_mutex);
    for (Warm& v : warm)
      if (v.thread == w.thread) {
        v = std::move(w);
        return;
      }
    if (warm.size() >= 64) warm.erase(warm.begin());  // threads that come and go: keep the latest
    warm.push_back(std::move(w));
  }

  // y (n_red x d, row-major) = A^-1 y by PCG from zero, each column's error 1e-6 of its
  // solution's A-norm (estimated as the forward solve's is)
  void adjoint_solve(std::vector<double>& y) const {
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Y(y.data(), n_red, d);
    const Eigen::MatrixXd B = Y;
    Eigen::MatrixXd Z = Eigen::MatrixXd::Zero(n_red, d);
    pcg->solve(B, Z, {1e-6, true}, max_iterations());
    Y = Z;
  }

  // Rows [row0, row0 + n d) of M for one pose X (n x d) by PCG from the thread's last solution.
  void iterative_solve(const MatrixIn& X, MatrixOut& M, Eigen::Index row0) const {
    Eigen::MatrixXd B(n_red, d);
    for (int c = 0; c < d; ++c) B.col(c) = rhs_op * X.col(c);
    Warm w = take_warm();
    if (w.sol.rows() != n_red) w.sol = Eigen::MatrixXd::Zero(n_red, d);
    try {
      w.iterations = pcg->solve(B, w.sol, forward_tolerance(), max_iterations());
    } catch (...) {
      w.sol.setZero();  // a failed solve is no start for the next one
      keep_warm(std::move(w));
      throw;
    }
    scatter([&](int a, int c) { return w.sol(a, c); }, M, row0);
    keep_warm(std::move(w));
  }

  bool use_cholmod() const {
    switch (opt.factorization) {
      case Factorization::Eigen: return false;
      case Factorization::Cholmod: return true;
      case Factorization::Automatic: break;
    }
    return detail::cholmod_available();
  }

  // sol (n_red x (frames d), row-major: frame f's d columns from f d on) for the right-hand sides
  // of `frames` poses X ((frames n) x d, frame f in rows [f n, f n + n)) by the factor, which
  // takes 8 columns at most.
  void sparse_solve(const MatrixIn& X, int frames, std::vector<double>& sol) const {
    // right-hand sides -beta H_mx X, row by row in parallel (rows of rhs_op: CSR); shared out
    // from a few thousand rows on, so that no serial stretch between the calls is long enough for
    // the pool's threads to fall asleep (a sleeping thread joins the next call late)
    const Eigen::Index W = static_cast<Eigen::Index>(frames) * d;
    sol.resize(static_cast<size_t>(n_red) * static_cast<size_t>(W));
    const int* outer = rhs_op.outerIndexPtr();
    const int* inner = rhs_op.innerIndexPtr();
    const double* val = rhs_op.valuePtr();
    const Eigen::Index is = X.innerStride(), ld = X.outerStride();
    const int nt = detail::thread_count(rhs_op.nonZeros() * frames, 1 << 14);
    double* out = sol.data();
    detail::parallel_blocks(n_red, 512, nt, [&](long long a0, long long a1) {
      for (int f = 0; f < frames; ++f) {
        const double* x = X.data() + static_cast<Eigen::Index>(f) * n * is;
        if (d == 3) rhs_rows<3>(outer, inner, val, x, is, ld, out + f * d, W, a0, a1);
        else rhs_rows<2>(outer, inner, val, x, is, ld, out + f * d, W, a0, a1);
      }
    });
    F.solve(sol.data(), static_cast<int>(W));
  }

  // Rows [row0, row0 + n d) of M from a reduced solution: sol(a, c) is unknown a's component c.
  template <class Sol>
  void scatter(const Sol& sol, MatrixOut& M, Eigen::Index row0) const {
    for (int i = 0; i < n; ++i)
      for (int r = 0; r < d; ++r) {
        const int a = reduced[static_cast<size_t>(i) * d + r];
        if (a < 0) continue;
        for (int c = 0; c < d; ++c) M(row0 + i * d + c, r) = sol(a, c);
      }
  }
  // a row-major reduced solution whose rows are W doubles apart
  static auto rows_of(const double* sol, Eigen::Index W) {
    return [sol, W](int a, int c) { return sol[a * W + c]; };
  }

  // M ((frames n d) x d) of `frames` poses X ((frames n) x d), checked by the caller. The map is
  // linear column by column (fact 11): the dense operator or the factor serves all the frames in
  // one pass. Scratch kept per thread, of the size of the frames of one call.
  void solve_frames(const MatrixIn& X, Eigen::Index frames, MatrixOut& M) const {
    M.setZero();
    if (n_red == 0) return;
    if (iterative) {
      for (Eigen::Index f = 0; f < frames; ++f) iterative_solve(X.middleRows(f * n, n), M, f * n * d);
      return;
    }
    thread_local std::vector<double> sol, cols;
    if (!dense) {
      const int group = 8 / d;  // the factor's 8 columns at a time
      for (Eigen::Index f0 = 0; f0 < frames; f0 += group) {
        const int g = static_cast<int>(std::min<Eigen::Index>(group, frames - f0));
        sparse_solve(X.middleRows(f0 * n, g * n), g, sol);
        for (int f = 0; f < g; ++f)
          scatter(rows_of(sol.data() + f * d, static_cast<Eigen::Index>(g) * d), M, (f0 + f) * n * d);
      }
      return;
    }
    // the frames' columns, 3 of n doubles a frame (z zero in 2D); the solutions n_red x 3 a frame
    const std::ptrdiff_t cn = 3 * static_cast<std::ptrdiff_t>(n), sn = 3 * static_cast<std::ptrdiff_t>(n_red);
    cols.assign(static_cast<size_t>(frames * cn), 0.0);
    sol.resize(static_cast<size_t>(frames * sn));
    for (Eigen::Index f = 0; f < frames; ++f)
      for (int c = 0; c < d; ++c)
        for (int j = 0; j < n; ++j) cols[static_cast<size_t>(f * cn + c * n + j)] = X(f * n + j, c);
    const std::ptrdiff_t rows = n_red;
    // one block of an even number of rows a thread (the kernel takes rows two at a time): the
    // caller, which takes the first, then reads the same part of K every frame and finds it in
    // its cache; within it, tiles of about 64 KB of K that every frame reads while it is cached
    const int nt = detail::thread_count(rows * n * frames, 1 << 17);
    const std::ptrdiff_t block = std::max<std::ptrdiff_t>(2, ((rows + nt - 1) / nt + 1) & ~std::ptrdiff_t(1));
    const std::ptrdiff_t tile = std::max<std::ptrdiff_t>(2, (8192 / n) & ~std::ptrdiff_t(1));
    const double* c0 = cols.data();
    double* s0 = sol.data();
    detail::parallel_blocks(rows, block, nt, [&](long long a, long long b) {
      for (long long r = a; r < b; r += tile)
        for (Eigen::Index f = 0; f < frames; ++f) {
          const double* cf = c0 + f * cn;
          dense_rows(K.data(), n, cf, cf + n, cf + 2 * static_cast<std::ptrdiff_t>(n), s0 + f * sn, r,
                     std::min<long long>(r + tile, b));
        }
    });
    for (Eigen::Index f = 0; f < frames; ++f) scatter(rows_of(s0 + f * sn, 3), M, f * n * d);
  }

  // The blocks on the reduced unknowns: R H R^T and R H_mx with R (n_red x d n) selecting them.
  struct Blocks {
    SpMat vibr_mm, disc_mm, disc_mx;
  };
  Blocks restricted(const detail::Hessians& H) const {
    return {restrict_to(H.vibr_mm, reduced, n_red, &reduced, n_red),
            restrict_to(H.disc_mm, reduced, n_red, &reduced, n_red),
            restrict_to(H.disc_mx, reduced, n_red, nullptr, n)};
  }

  // Factors for `a` and commits alpha, the factor and the dense operator only when all succeed
  // (a failing set_alpha leaves the solver as it was).
  void factor(double a, const Blocks& R) {
    if (n_red == 0) {
      alpha = a;
      return;
    }
    const SpMat A = a * R.vibr_mm + beta * R.disc_mm;
    if (iterative) {
      auto P = std::make_unique<detail::PcgSolver>(A);
      alpha = a;
      pcg = std::move(P);
      std::lock_guard<std::mutex> lock(warm_mutex);
      warm.clear();  // the starts belong to the old matrix
      return;
    }
    detail::CholeskyFactor Fa = detail::cholesky(A, use_cholmod());
    std::vector<double> Ka;
    if (dense) {
      // K = -beta A^-1 H_mx, 8 columns (vertices) per pass over the factor
      Ka.assign(static_cast<size_t>(n_red) * n, 0.0);
      constexpr int W = 8;
      std::vector<double> B(static_cast<size_t>(n_red) * W);
      for (int j0 = 0; j0 < n; j0 += W) {
        const int w = std::min(W, n - j0);
        std::fill(B.begin(), B.end(), 0.0);
        // column j of R H_mx (CSC): scatter its entries
        for (int c = 0; c < w; ++c)
          for (SpMat::InnerIterator it(R.disc_mx, j0 + c); it; ++it)
            B[static_cast<size_t>(it.row()) * w + c] = -beta * it.value();
        Fa.solve(B.data(), w);
        for (int r = 0; r < n_red; ++r)
          for (int c = 0; c < w; ++c) Ka[static_cast<size_t>(r) * n + j0 + c] = B[static_cast<size_t>(r) * w + c];
      }
    }
    alpha = a;
    F = std::move(Fa);
    K = std::move(Ka);
  }
};

ModifiedBI::ModifiedBI(const Eigen::Ref<const Eigen::MatrixXd>& U,
                       const Eigen::Ref<const Eigen::MatrixXi>& T, const Options& options)
    : impl_(std::make_unique<Impl>()) {
  validate_mesh(U, T);
  Impl& I = *impl_;
  I.U = U;
  I.T = T;
  I.d = static_cast<int>(U.cols());
  I.n = static_cast<int>(U.rows());
  I.m = static_cast<int>(T.rows());
  I.opt = options;
  const int d = I.d, n = I.n;
  I.alpha = resolve_alpha(options, d);
  check_beta(options);
  check_max_memory(options);

  const detail::Hessians H = detail::assemble(I.U, I.T);
  if (H.disc_mm.nonZeros() == 0)
    throw Error("the control mesh has no interior faces (a single element?); "
                "modified-BI needs at least two face-adjacent elements");
  // beta: equal Frobenius norms of the m-blocks of E_vibr and beta E_disc (fact 7).
  I.beta = options.beta > 0 ? options.beta : H.vibr_mm.norm() / H.disc_mm.norm();

  std::vector<char> free_vertex(n, 0);
  for (int e = 0; e < I.m; ++e)
    for (int j = 0; j <= d; ++j) free_vertex[T(e, j)] = 1;
  if (options.pin_boundary) {
    const Eigen::VectorXi b = boundary_vertices(n, T);
    for (int i = 0; i < n; ++i)
      if (b(i)) free_vertex[i] = 0;
  }
  const std::vector<char> pinned = detail::gauge_pins(I.U, I.T, free_vertex, I.null_dim);
  I.reduced.assign(static_cast<size_t>(d) * n, -1);
  for (int i = 0; i < n; ++i)
    for (int r = 0; r < d; ++r)
      if (free_vertex[i] && !pinned[static_cast<size_t>(i) * d + r]) I.reduced[i * d + r] = I.n_red++;

  const Impl::Blocks R = I.restricted(H);
  switch (options.solve_path) {
    case SolvePath::Dense: I.dense = true; break;
    case SolvePath::Sparse: I.dense = false; break;
    case SolvePath::Iterative: I.iterative = true; break;
    case SolvePath::Automatic:
      I.dense = static_cast<long long>(I.n_red) * n <= kDenseOperatorMaxEntries;
      I.iterative = !I.dense && factor_would_not_fit(U, T, options);
      break;
  }
  if (I.iterative) {
    I.model_size = (I.U.colwise().maxCoeff() - I.U.colwise().minCoeff()).norm();
    I.position_scale = position_scale(I.U, I.T);
  }
  I.rhs_op = -I.beta * R.disc_mx;
  if (I.dense && static_cast<long long>(I.n_red) * n > (1LL << 28))
    throw Error("the dense operator would need " + std::to_string(I.n_red) + " x " +
                std::to_string(n) + " doubles; use SolvePath::Sparse or Automatic");
  if (options.factorization == Factorization::Cholmod && !detail::cholmod_available())
    throw Error("Factorization::Cholmod asked for, but this build has no CHOLMOD "
                "(configure with MBI_WITH_CHOLMOD=ON and libsuitesparse-dev)");
  I.factor(I.alpha, R);
  warm_up();
}

// One solve at rest, discarded: it leaves the factor (or the dense operator) in the caches, the
// solve's buffers allocated and the pool's threads awake, so that the caller's first solve
// costs what the later ones do.
void ModifiedBI::warm_up() const { (void)solve(impl_->U); }

ModifiedBI::~ModifiedBI() = default;
ModifiedBI::ModifiedBI(ModifiedBI&&) noexcept = default;
ModifiedBI& ModifiedBI::operator=(ModifiedBI&&) noexcept = default;

void ModifiedBI::set_alpha(double alpha) {
  const Impl& I = *impl_;
  impl_->factor(check_alpha(alpha), I.restricted(detail::assemble(I.U, I.T)));
  warm_up();
}

int ModifiedBI::dim() const { return impl_->d; }
int ModifiedBI::vertices() const { return impl_->n; }
int ModifiedBI::elements() const { return impl_->m; }
double ModifiedBI::alpha() const { return impl_->alpha; }
double ModifiedBI::beta() const { return impl_->beta; }
bool ModifiedBI::pin_boundary() const { return impl_->opt.pin_boundary; }
int ModifiedBI::null_space_dim() const { return impl_->null_dim; }
int ModifiedBI::unknowns() const { return impl_->n_red; }
bool ModifiedBI::dense_operator() const { return impl_->dense; }
SolvePath ModifiedBI::solve_path() const {
  return impl_->iterative ? SolvePath::Iterative : impl_->dense ? SolvePath::Dense : SolvePath::Sparse;
}
std::string ModifiedBI::factorization() const {
  return impl_->iterative ? "none: PCG, incomplete Cholesky (AMD) preconditioner" : impl_->F.method;
}
int ModifiedBI::iterations() const {
  const Impl& I = *impl_;
  std::lock_guard<std::mutex> lock(I.warm_mutex);
  for (const Impl::Warm& w : I.warm)
    if (w.thread == std::this_thread::get_id()) return w.iterations;
  return 0;
}
long long ModifiedBI::factor_nonzeros() const {
  return impl_->pcg ? impl_->pcg->preconditioner_nonzeros() : impl_->F.nonzeros();
}
long long ModifiedBI::factor_stored_values() const { return static_cast<long long>(impl_->F.stored_values()); }
long long ModifiedBI::factor_index_bytes() const { return static_cast<long long>(impl_->F.index_bytes()); }
long long ModifiedBI::memory_bytes() const {
  const Impl& I = *impl_;
  const auto bytes = [](auto count, size_t each) { return static_cast<long long>(count) * static_cast<long long>(each); };
  return static_cast<long long>(I.F.bytes()) + static_cast<long long>(I.pcg ? I.pcg->bytes() : 0) +
         bytes(I.K.size(), sizeof(double)) +
         bytes(I.rhs_op.nonZeros(), sizeof(double) + sizeof(int)) + bytes(I.rhs_op.outerSize() + 1, sizeof(int)) +
         bytes(I.reduced.size(), sizeof(int)) + bytes(I.U.size(), sizeof(double)) + bytes(I.T.size(), sizeof(int));
}
SpMat ModifiedBI::vibr_hessian_mm() const { return detail::assemble(impl_->U, impl_->T).vibr_mm; }
SpMat ModifiedBI::disc_hessian_mm() const { return detail::assemble(impl_->U, impl_->T).disc_mm; }
SpMat ModifiedBI::disc_hessian_mx() const { return detail::assemble(impl_->U, impl_->T).disc_mx; }
SpMat ModifiedBI::disc_hessian_xx() const { return detail::assemble(impl_->U, impl_->T).disc_xx; }
const Eigen::MatrixXd& ModifiedBI::rest_positions() const { return impl_->U; }
const Eigen::MatrixXi& ModifiedBI::elements_matrix() const { return impl_->T; }

namespace {
void check_out(const char* what, Eigen::Index rows, Eigen::Index cols, Eigen::Index want_rows, Eigen::Index want_cols) {
  if (rows != want_rows || cols != want_cols)
    throw Error(std::string(what) + " must be " + std::to_string(want_rows) + " x " + std::to_string(want_cols) +
                ", got " + std::to_string(rows) + " x " + std::to_string(cols));
}

// solve()'s checks: X (n x d, finite) and M ((n d) x d).
void check_solve(int n, int d, const Eigen::Ref<const Eigen::MatrixXd>& X, const MatrixOut& M) {
  if (X.rows() != n || X.cols() != d)
    throw Error("X must be " + std::to_string(n) + " x " + std::to_string(d) +
                ", got " + std::to_string(X.rows()) + " x " + std::to_string(X.cols()));
  check_out("M", M.rows(), M.cols(), static_cast<Eigen::Index>(d) * n, d);
  detail::check_finite("control vertex", X);
}

// solve_transpose()'s checks: G ((n d) x d, finite) and GX (n x d).
void check_solve_transpose(int n, int d, const Eigen::Ref<const Eigen::MatrixXd>& G, const Eigen::Ref<Eigen::MatrixXd>& GX) {
  if (G.rows() != static_cast<Eigen::Index>(n) * d || G.cols() != d)
    throw Error("dL/dM must be " + std::to_string(n * d) + " x " + std::to_string(d) + ", got " +
                std::to_string(G.rows()) + " x " + std::to_string(G.cols()));
  check_out("dL/dX", GX.rows(), GX.cols(), n, d);
  detail::check_finite("dL/dM row", G);
}
}  // namespace

VertexMatrices ModifiedBI::solve(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  VertexMatrices M(static_cast<Eigen::Index>(impl_->d) * impl_->n, impl_->d);
  solve(X, M);
  return M;
}

void ModifiedBI::solve(const Eigen::Ref<const Eigen::MatrixXd>& X, MatrixOut M) const {
  const Impl& I = *impl_;
  check_solve(I.n, I.d, X, M);
  I.solve_frames(X, 1, M);
}

void ModifiedBI::solve_batch(const MatrixIn& X, MatrixOut M) const {
  const Impl& I = *impl_;
  const int d = I.d, n = I.n;
  if (X.cols() != d || X.rows() % n != 0)
    throw Error("poses must be (frames " + std::to_string(n) + ") x " + std::to_string(d) + ", got " +
                std::to_string(X.rows()) + " x " + std::to_string(X.cols()));
  const Eigen::Index frames = X.rows() / n;
  check_out("M", M.rows(), M.cols(), frames * n * d, d);
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (int c = 0; c < d; ++c)
      if (!std::isfinite(X(i, c)))
        throw Error("control vertex " + std::to_string(i % n) + " of pose " + std::to_string(i / n) +
                    " has a non-finite coordinate (column " + std::to_string(c) + ")");
  I.solve_frames(X, frames, M);
}

Eigen::MatrixXd ModifiedBI::solve_transpose(const VertexMatrices& G) const {
  Eigen::MatrixXd GX(impl_->n, impl_->d);
  solve_transpose(G, GX);
  return GX;
}

void ModifiedBI::solve_transpose(const Eigen::Ref<const Eigen::MatrixXd>& G, Eigen::Ref<Eigen::MatrixXd> GX) const {
  const Impl& I = *impl_;
  const int d = I.d, n = I.n;
  check_solve_transpose(n, d, G, GX);
  GX.setZero();
  if (I.n_red == 0) return;
  // solve() writes M(i d + c, r) = sol(a, c), a = reduced[i d + r]: gather G the same way
  thread_local std::vector<double> y;
  y.assign(static_cast<size_t>(I.n_red) * d, 0.0);
  for (int i = 0; i < n; ++i)
    for (int r = 0; r < d; ++r) {
      const int a = I.reduced[i * d + r];
      if (a < 0) continue;
      for (int c = 0; c < d; ++c) y[static_cast<size_t>(a) * d + c] = G(i * d + c, r);
    }
  // sol = -beta A^-1 R H_mx X with A symmetric: dL/dX = (-beta R H_mx)^T A^-1 dL/dsol
  if (I.iterative) I.adjoint_solve(y);
  else I.F.solve(y.data(), d);
  for (int a = 0; a < I.n_red; ++a)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(I.rhs_op, a); it; ++it)
      for (int c = 0; c < d; ++c) GX(it.col(), c) += it.value() * y[static_cast<size_t>(a) * d + c];
}

void ModifiedBI::solve_vertices(const Eigen::Ref<const Eigen::MatrixXd>& X, std::span<const int> vertices,
                                MatrixOut M) const {
  const Impl& I = *impl_;
  if (!I.dense) return solve(X, M);
  const int d = I.d, n = I.n;
  check_solve(n, d, X, M);
  detail::check_index_list("vertices", vertices, n);
  thread_local std::vector<double> cols, sol;
  thread_local std::vector<char> have;  // per pair of the operator's rows: computed
  cols.assign(3 * static_cast<size_t>(n), 0.0);
  for (int c = 0; c < d; ++c)
    for (int j = 0; j < n; ++j) cols[static_cast<size_t>(c * n + j)] = X(j, c);
  sol.resize(3 * static_cast<size_t>(I.n_red));
  have.assign((static_cast<size_t>(I.n_red) + 1) / 2, 0);
  for (int i : vertices)
    for (int r = 0; r < d; ++r) {
      const int a = I.reduced[static_cast<size_t>(i) * d + r];
      if (a >= 0 && !have[static_cast<size_t>(a / 2)]) {
        // the pair of rows solve() computes together (its blocks and tiles start at even rows):
        // the same arithmetic, so the same bits
        const std::ptrdiff_t r0 = a & ~1, r1 = std::min<std::ptrdiff_t>(r0 + 2, I.n_red);
        dense_rows(I.K.data(), n, cols.data(), cols.data() + n, cols.data() + 2 * n, sol.data(), r0, r1);
        have[static_cast<size_t>(a / 2)] = 1;
      }
      for (int c = 0; c < d; ++c) M(i * d + c, r) = a < 0 ? 0.0 : sol[3 * static_cast<size_t>(a) + static_cast<size_t>(c)];
    }
}

void ModifiedBI::solve_transpose_vertices(const Eigen::Ref<const Eigen::MatrixXd>& G, std::span<const int> vertices,
                                          Eigen::Ref<Eigen::MatrixXd> GX) const {
  const Impl& I = *impl_;
  if (!I.dense) return solve_transpose(G, GX);
  const int d = I.d, n = I.n;
  check_solve_transpose(n, d, G, GX);
  detail::check_index_list("vertices", vertices, n);
  // GX(j, c) = sum over the listed rows a of K(a, j) G(i d + c, r), a = reduced[i d + r] (solve()'s
  // M(i d + c, r) = K(a, :) X(:, c)); each vertex once
  thread_local std::vector<double> acc;
  thread_local std::vector<char> seen;
  acc.assign(3 * static_cast<size_t>(n), 0.0);
  seen.assign(static_cast<size_t>(n), 0);
  for (int i : vertices) {
    if (seen[static_cast<size_t>(i)]) continue;
    seen[static_cast<size_t>(i)] = 1;
    for (int r = 0; r < d; ++r) {
      const int a = I.reduced[static_cast<size_t>(i) * d + r];
      if (a < 0) continue;
      double y[3] = {};
      for (int c = 0; c < d; ++c) y[c] = G(i * d + c, r);
      const double* k = I.K.data() + static_cast<std::ptrdiff_t>(a) * n;
      double *ax = acc.data(), *ay = ax + n, *az = ay + n;  // a column each: the loop vectorises
      for (int j = 0; j < n; ++j) {
        ax[j] += k[j] * y[0];
        ay[j] += k[j] * y[1];
        az[j] += k[j] * y[2];
      }
    }
  }
  for (int c = 0; c < d; ++c)
    for (int j = 0; j < n; ++j) GX(j, c) = acc[static_cast<size_t>(c) * n + static_cast<size_t>(j)];
}

BezierPoints ModifiedBI::bezier(const Eigen::Ref<const Eigen::MatrixXd>& X, const VertexMatrices& M) const {
  return bezier_points(impl_->U, impl_->T, X, M);
}

namespace {
void check_xm(int n, int d, const Eigen::Ref<const Eigen::MatrixXd>& X, const MatrixIn& M) {
  if (X.rows() != n || X.cols() != d)
    throw Error("X must be " + std::to_string(n) + " x " + std::to_string(d) +
                ", got " + std::to_string(X.rows()) + " x " + std::to_string(X.cols()));
  if (M.rows() != static_cast<Eigen::Index>(n) * d || M.cols() != d)
    throw Error("M must be " + std::to_string(n * d) + " x " + std::to_string(d) +
                ", got " + std::to_string(M.rows()) + " x " + std::to_string(M.cols()));
}
}  // namespace

BezierPoints bezier_bi(const Eigen::Ref<const Eigen::MatrixXd>& X,
                       const Eigen::Ref<const Eigen::MatrixXi>& T) {
  if ((X.cols() != 2 && X.cols() != 3) || T.cols() != X.cols() + 1)
    throw Error("X must be n x d (d = 2, 3) and T m x (d+1)");
  BezierPoints B(T.rows() * ((X.cols() + 1) * (X.cols() + 2) / 2), X.cols());
  bezier_bi(X, T, B);
  return B;
}

void bezier_bi(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::MatrixXi>& T, MatrixOut B) {
  const int d = static_cast<int>(X.cols());
  if ((d != 2 && d != 3) || T.cols() != d + 1)
    throw Error("X must be n x d (d = 2, 3) and T m x (d+1)");
  const int K = (d + 1) * (d + 2) / 2;
  check_out("the Bezier points", B.rows(), B.cols(), T.rows() * K, d);
  for (Eigen::Index e = 0; e < T.rows(); ++e)
    for (int k = 0; k <= d; ++k)
      if (T(e, k) < 0 || T(e, k) >= X.rows())
        throw Error("element " + std::to_string(e) + " has vertex index " +
                    std::to_string(T(e, k)) + " outside [0, " + std::to_string(X.rows()) + ")");
  detail::bezier_rows(X, T, X, nullptr, B);
}

BezierPoints bezier_points(const Eigen::Ref<const Eigen::MatrixXd>& U,
                           const Eigen::Ref<const Eigen::MatrixXi>& T,
                           const Eigen::Ref<const Eigen::MatrixXd>& X, const VertexMatrices& M) {
  detail::check_shapes(U, T);
  BezierPoints B(T.rows() * ((U.cols() + 1) * (U.cols() + 2) / 2), U.cols());
  bezier_points(U, T, X, M, B);
  return B;
}

void bezier_points(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                   const Eigen::Ref<const Eigen::MatrixXd>& X, const MatrixIn& M, MatrixOut B) {
  detail::check_shapes(U, T);
  const int d = static_cast<int>(U.cols());
  const int n = static_cast<int>(U.rows());
  check_xm(n, d, X, M);
  const int K = (d + 1) * (d + 2) / 2;
  check_out("the Bezier points", B.rows(), B.cols(), T.rows() * K, d);
  detail::bezier_rows(U, T, X, &M, B);
}

void bezier_points(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                   const Eigen::Ref<const Eigen::MatrixXd>& X, const MatrixIn& M, std::span<const int> elements,
                   MatrixOut B) {
  detail::check_shapes(U, T);
  const int d = static_cast<int>(U.cols());
  check_xm(static_cast<int>(U.rows()), d, X, M);
  check_out("the Bezier points", B.rows(), B.cols(), T.rows() * ((d + 1) * (d + 2) / 2), d);
  detail::check_index_list("elements", elements, T.rows());
  detail::bezier_rows(U, T, X, &M, B, elements, true);
}

Eigen::VectorXd evaluate_reference(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                   const Eigen::Ref<const Eigen::MatrixXi>& T,
                                   const Eigen::Ref<const Eigen::MatrixXd>& X,
                                   const VertexMatrices& M, int e,
                                   const Eigen::Ref<const Eigen::VectorXd>& u) {
  const int d = static_cast<int>(U.cols());
  check_xm(static_cast<int>(U.rows()), d, X, M);
  if (u.size() != d) throw Error("u must have " + std::to_string(d) + " entries");
  const Eigen::MatrixXd A = basis_gradients(U, T, e);  // checks e
  const Eigen::VectorXd r = u - U.row(T(e, 0)).transpose();
  Eigen::VectorXd phi(d + 1);
  phi.tail(d) = A.bottomRows(d) * r;
  phi(0) = 1.0 - phi.tail(d).sum();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(d);
  for (int k = 0; k <= d; ++k) {
    const int i = T(e, k);
    const Eigen::VectorXd w = u - U.row(i).transpose();
    const Eigen::VectorXd xi = X.row(i).transpose() + M.middleRows(i * d, d) * w;
    x += phi(k) * xi;
  }
  return x;
}

}  // namespace mbi::interp
