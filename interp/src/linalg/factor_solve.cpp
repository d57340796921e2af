// The per-frame solve with a sparse Cholesky factor: triangular sweeps over the supernodes for
// all right-hand sides at once (see factor.hpp), serially or shared out between the library's
// threads along the factor's schedule (CholeskyFactor::schedule).
#include "linalg/factor.hpp"

#include "runtime/cpu.hpp"
#include "runtime/threads.hpp"

#include <mbi/error.hpp>

#include <algorithm>
#include <cstring>
#include <thread>
#include <vector>

namespace mbi::interp::detail {

namespace {

// A row of X (the S right-hand sides of one unknown) as one vector of the compiler (GCC/Clang
// vector extensions: AVX2 registers in the avx2 build of the sweeps, SSE pairs otherwise), loaded
// and stored without alignment assumptions. Written as vectors, not loops over S: the compiler
// left those loops scalar.
#if defined(__GNUC__) && !defined(__clang__)
// load/store/the kernels pass vectors by value only inside always-inlined code: no ABI involved
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
template <int S>
struct RowVec {
  typedef double type __attribute__((vector_size(S * sizeof(double))));
};
template <int S>
using Vec = typename RowVec<S>::type;

template <int S>
__attribute__((always_inline)) inline Vec<S> load(const double* p) {
  Vec<S> v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <int S>
__attribute__((always_inline)) inline void store(double* p, const Vec<S>& v) {
  std::memcpy(p, &v, sizeof v);
}

// Forward L y = b and backward L^T x = y, one supernode at a time, in panels of P columns; X
// holds S doubles a row (the right-hand sides, padded). A panel's P x P triangle is solved in
// registers, then one pass over every row below it (the rest of the diagonal block and the rows
// below the supernode alike: row i of the supernode is X's row rmap[i]) applies its P columns:
// each such row of X is loaded and stored once per panel, and the backward sums run in P
// independent accumulators. `rmap` is F.rows, or F.prow for a group of the threaded forward
// sweep (the supernode's own columns come first in both).
// Columns of a panel: 8 while the panel's vectors fit the 16 AVX2 registers (S <= 4), else 4.
template <int S>
constexpr int kPanel = S <= 4 ? 8 : 4;

template <int S, int W>
__attribute__((always_inline)) inline void forward_panel(const double* L, std::ptrdiff_t nsrow, int j,
                                                         const int* r, double* X, double* Xs) {
  const double* c[W];
  Vec<S> y[W];
  for (int k = 0; k < W; ++k) {
    c[k] = L + (j + k) * nsrow;
    Vec<S> x = load<S>(Xs + (j + k) * S);
    for (int q = 0; q < k; ++q) x -= c[q][j + k] * y[q];
    y[k] = x * (1.0 / c[k][j + k]);
    store<S>(Xs + (j + k) * S, y[k]);
  }
  for (std::ptrdiff_t i = j + W; i < nsrow; ++i) {
    double* xi = X + static_cast<std::ptrdiff_t>(r[i]) * S;
    Vec<S> acc = c[0][i] * y[0];
    for (int k = 1; k < W; ++k) acc += c[k][i] * y[k];
    store<S>(xi, load<S>(xi) - acc);
  }
}

template <int S, int W>
__attribute__((always_inline)) inline void backward_panel(const double* L, std::ptrdiff_t nsrow, int j,
                                                          const int* r, double* X, double* Xs) {
  const double* c[W];
  Vec<S> a[W];
  for (int k = 0; k < W; ++k) {
    c[k] = L + (j + k) * nsrow;
    a[k] = Vec<S>{};
  }
  for (std::ptrdiff_t i = j + W; i < nsrow; ++i) {
    const Vec<S> xi = load<S>(X + static_cast<std::ptrdiff_t>(r[i]) * S);
    for (int k = 0; k < W; ++k) a[k] += c[k][i] * xi;
  }
  Vec<S> x[W];
  for (int k = W - 1; k >= 0; --k) {
    Vec<S> v = load<S>(Xs + (j + k) * S) - a[k];
    for (int q = k + 1; q < W; ++q) v -= c[k][j + q] * x[q];
    x[k] = v * (1.0 / c[k][j + k]);
    store<S>(Xs + (j + k) * S, x[k]);
  }
}

template <int S>
__attribute__((always_inline)) inline void forward_super(const CholeskyFactor& F, int s, double* X,
                                                         const int* rmap) {
  const int k1 = F.super[s], nscol = F.super[s + 1] - k1;
  const std::ptrdiff_t nsrow = F.rowp[s + 1] - F.rowp[s];
  const int* r = rmap + F.rowp[s];
  const double* L = F.vals.data() + F.valp[s];
  double* Xs = X + static_cast<std::ptrdiff_t>(k1) * S;
  constexpr int P = kPanel<S>;
  int j = 0;
  for (; j + P <= nscol; j += P) forward_panel<S, P>(L, nsrow, j, r, X, Xs);
  switch (nscol - j) {
    case 7: forward_panel<S, 7>(L, nsrow, j, r, X, Xs); break;
    case 6: forward_panel<S, 6>(L, nsrow, j, r, X, Xs); break;
    case 5: forward_panel<S, 5>(L, nsrow, j, r, X, Xs); break;
    case 4: forward_panel<S, 4>(L, nsrow, j, r, X, Xs); break;
    case 3: forward_panel<S, 3>(L, nsrow, j, r, X, Xs); break;
    case 2: forward_panel<S, 2>(L, nsrow, j, r, X, Xs); break;
    case 1: forward_panel<S, 1>(L, nsrow, j, r, X, Xs); break;
    default: break;
  }
}

template <int S>
__attribute__((always_inline)) inline void backward_super(const CholeskyFactor& F, int s, double* X) {
  const int k1 = F.super[s], nscol = F.super[s + 1] - k1;
  const std::ptrdiff_t nsrow = F.rowp[s + 1] - F.rowp[s];
  const int* r = F.rows.data() + F.rowp[s];
  const double* L = F.vals.data() + F.valp[s];
  double* Xs = X + static_cast<std::ptrdiff_t>(k1) * S;
  constexpr int P = kPanel<S>;
  const int full = nscol / P * P;  // the same panels as forward_super, last first
  switch (nscol - full) {
    case 7: backward_panel<S, 7>(L, nsrow, full, r, X, Xs); break;
    case 6: backward_panel<S, 6>(L, nsrow, full, r, X, Xs); break;
    case 5: backward_panel<S, 5>(L, nsrow, full, r, X, Xs); break;
    case 4: backward_panel<S, 4>(L, nsrow, full, r, X, Xs); break;
    case 3: backward_panel<S, 3>(L, nsrow, full, r, X, Xs); break;
    case 2: backward_panel<S, 2>(L, nsrow, full, r, X, Xs); break;
    case 1: backward_panel<S, 1>(L, nsrow, full, r, X, Xs); break;
    default: break;
  }
  for (int j = full - P; j >= 0; j -= P) backward_panel<S, P>(L, nsrow, j, r, X, Xs);
}

// A sweep over a list of supernodes (ascending; the backward sweep walks it from the end), or
// over all of them when list is null.
template <int S>
__attribute__((always_inline)) inline void sweep_body(const CholeskyFactor& F, const std::vector<int>* list,
                                                      bool forward, double* X, const int* rmap) {
  const int ns = list ? static_cast<int>(list->size()) : static_cast<int>(F.super.size()) - 1;
  if (forward) {
    for (int k = 0; k < ns; ++k) forward_super<S>(F, list ? (*list)[k] : k, X, rmap);
  } else {
    for (int k = ns - 1; k >= 0; --k) backward_super<S>(F, list ? (*list)[k] : k, X);
  }
}

// The top part of a threaded solve: supernodes of at least F.top_split entries are shared out in
// blocks of kTopBlock columns, each block one step of the job (Steps). Forward, the caller solves
// the block's triangle, then every thread of the job updates chunks of kTopRows rows below it;
// backward, every thread sums chunks of the rows below into the chunk's own partial sums, then
// the caller adds them in chunk order and solves the triangle. The chunks do not depend on the
// number of threads, nor, therefore, do the sums. Smaller supernodes run on the caller. A thread
// claims several chunks at a time (about two claims a thread a step): each claim moves the
// claim word's cache line between cores, which costs as much as a chunk's arithmetic.
constexpr int kTopBlock = 16;
constexpr std::ptrdiff_t kTopRows = 128;

// rows claimed at a time out of `rows` shared by `threads` threads: whole chunks
std::ptrdiff_t top_grain(std::ptrdiff_t rows, int threads) {
  const std::ptrdiff_t chunks = (rows + kTopRows - 1) / kTopRows;
  return std::max<std::ptrdiff_t>(1, chunks / (2 * std::max(1, threads))) * kTopRows;
}

// rows [lo, hi) of supernode block columns j .. j+B: X[r[i]] -= sum_k L(i, j+k) y_k
template <int S>
__attribute__((always_inline)) inline void top_rows_forward(const double* L, std::ptrdiff_t nsrow, int j, int B,
                                                            const int* r, double* X, const double* y,
                                                            std::ptrdiff_t lo, std::ptrdiff_t hi) {
  for (int k0 = 0; k0 < B; k0 += 4) {
    const int w = std::min(4, B - k0);
    const double* c0 = L + static_cast<std::ptrdiff_t>(j + k0) * nsrow;
    const double* c1 = c0 + nsrow;
    const double* c2 = c1 + nsrow;
    const double* c3 = c2 + nsrow;
    const Vec<S> y0 = load<S>(y + k0 * S), y1 = w > 1 ? load<S>(y + (k0 + 1) * S) : Vec<S>{},
                 y2 = w > 2 ? load<S>(y + (k0 + 2) * S) : Vec<S>{}, y3 = w > 3 ? load<S>(y + (k0 + 3) * S) : Vec<S>{};
    if (w == 4) {
      for (std::ptrdiff_t i = lo; i < hi; ++i) {
        double* xi = X + static_cast<std::ptrdiff_t>(r[i]) * S;
        store<S>(xi, load<S>(xi) - ((c0[i] * y0 + c1[i] * y1) + (c2[i] * y2 + c3[i] * y3)));
      }
    } else {
      for (std::ptrdiff_t i = lo; i < hi; ++i) {
        double* xi = X + static_cast<std::ptrdiff_t>(r[i]) * S;
        Vec<S> acc = c0[i] * y0;
        if (w > 1) acc += c1[i] * y1;
        if (w > 2) acc += c2[i] * y2;
        store<S>(xi, load<S>(xi) - acc);
      }
    }
  }
}

// part (B x S) = sum over rows [lo, hi) of L(i, j+k) X[r[i]], k < B
template <int S>
__attribute__((always_inline)) inline void top_rows_backward(const double* L, std::ptrdiff_t nsrow, int j, int B,
                                                             const int* r, const double* X, double* part,
                                                             std::ptrdiff_t lo, std::ptrdiff_t hi) {
  for (int k0 = 0; k0 < B; k0 += 4) {
    const int w = std::min(4, B - k0);
    const double* c0 = L + static_cast<std::ptrdiff_t>(j + k0) * nsrow;
    const double* c1 = w > 1 ? c0 + nsrow : c0;
    const double* c2 = w > 2 ? c0 + 2 * nsrow : c0;
    const double* c3 = w > 3 ? c0 + 3 * nsrow : c0;
    Vec<S> a0 = {}, a1 = {}, a2 = {}, a3 = {};
    for (std::ptrdiff_t i = lo; i < hi; ++i) {
      const Vec<S> xi = load<S>(X + static_cast<std::ptrdiff_t>(r[i]) * S);
      a0 += c0[i] * xi;
      a1 += c1[i] * xi;
      a2 += c2[i] * xi;
      a3 += c3[i] * xi;
    }
    const Vec<S> a[4] = {a0, a1, a2, a3};
    for (int k = 0; k < w; ++k) store<S>(part + (k0 + k) * S, a[k]);
  }
}

using TopForward = void (*)(const double*, std::ptrdiff_t, int, int, const int*, double*, const double*,
                            std::ptrdiff_t, std::ptrdiff_t);
using TopBackward = void (*)(const double*, std::ptrdiff_t, int, int, const int*, const double*, double*,
                             std::ptrdiff_t, std::ptrdiff_t);
using OneSuper = void (*)(const CholeskyFactor&, int, bool, double*);

template <int S>
void top_forward_plain(const double* L, std::ptrdiff_t nsrow, int j, int B, const int* r, double* X,
                       const double* y, std::ptrdiff_t lo, std::ptrdiff_t hi) {
  top_rows_forward<S>(L, nsrow, j, B, r, X, y, lo, hi);
}
template <int S>
void top_backward_plain(const double* L, std::ptrdiff_t nsrow, int j, int B, const int* r, const double* X,
                        double* part, std::ptrdiff_t lo, std::ptrdiff_t hi) {
  top_rows_backward<S>(L, nsrow, j, B, r, X, part, lo, hi);
}
template <int S>
void one_super_plain(const CholeskyFactor& F, int s, bool forward, double* X) {
  if (forward) forward_super<S>(F, s, X, F.rows.data());
  else backward_super<S>(F, s, X);
}
#ifdef MBI_INTERP_X86
template <int S>
__attribute__((target("avx2,fma"))) void top_forward_avx2(const double* L, std::ptrdiff_t nsrow, int j, int B,
                                                          const int* r, double* X, const double* y,
                                                          std::ptrdiff_t lo, std::ptrdiff_t hi) {
  top_rows_forward<S>(L, nsrow, j, B, r, X, y, lo, hi);
}
template <int S>
__attribute__((target("avx2,fma"))) void top_backward_avx2(const double* L, std::ptrdiff_t nsrow, int j, int B,
                                                           const int* r, const double* X, double* part,
                                                           std::ptrdiff_t lo, std::ptrdiff_t hi) {
  top_rows_backward<S>(L, nsrow, j, B, r, X, part, lo, hi);
}
template <int S>
__attribute__((target("avx2,fma"))) void one_super_avx2(const CholeskyFactor& F, int s, bool forward, double* X) {
  if (forward) forward_super<S>(F, s, X, F.rows.data());
  else backward_super<S>(F, s, X);
}
#endif

// The caller's side of the top part (see above); partial: chunks x kTopBlock x S doubles, ytop:
// kTopBlock x S.
template <int S>
void top_part(const CholeskyFactor& F, double* X, double* partial, double* ytop, Steps& steps, int threads) {
  TopForward fwd = top_forward_plain<S>;
  TopBackward bwd = top_backward_plain<S>;
  OneSuper one = one_super_plain<S>;
#ifdef MBI_INTERP_X86
  if (have_avx2_fma()) fwd = top_forward_avx2<S>, bwd = top_backward_avx2<S>, one = one_super_avx2<S>;
#endif
  auto big = [&](int s) {
    return static_cast<std::ptrdiff_t>(F.super[s + 1] - F.super[s]) * (F.rowp[s + 1] - F.rowp[s]) >= F.top_split;
  };
  for (int s : F.top) {
    if (!big(s)) {
      one(F, s, true, X);
      continue;
    }
    const int k1 = F.super[s], nscol = F.super[s + 1] - k1;
    const std::ptrdiff_t nsrow = F.rowp[s + 1] - F.rowp[s];
    const int* r = F.rows.data() + F.rowp[s];
    const double* L = F.vals.data() + F.valp[s];
    double* Xs = X + static_cast<std::ptrdiff_t>(k1) * S;
    for (int j = 0; j < nscol; j += kTopBlock) {
      const int B = std::min(kTopBlock, nscol - j);
      Vec<S> y[kTopBlock];
      for (int k = 0; k < B; ++k) {
        const double* ck = L + static_cast<std::ptrdiff_t>(j + k) * nsrow;
        Vec<S> v = load<S>(Xs + (j + k) * S);
        for (int q = 0; q < k; ++q) v -= L[static_cast<std::ptrdiff_t>(j + q) * nsrow + j + k] * y[q];
        y[k] = v * (1.0 / ck[j + k]);
        store<S>(ytop + k * S, y[k]);
      }
      const std::ptrdiff_t first = j + B;
      steps.run(nsrow - first, top_grain(nsrow - first, threads), [&](long long b, long long e) {
        fwd(L, nsrow, j, B, r, X, ytop, first + b, first + e);
      });
      for (int k = 0; k < B; ++k) store<S>(Xs + (j + k) * S, y[k]);
    }
  }
  for (auto it = F.top.rbegin(); it != F.top.rend(); ++it) {
    const int s = *it;
    if (!big(s)) {
      one(F, s, false, X);
      continue;
    }
    const int k1 = F.super[s], nscol = F.super[s + 1] - k1;
    const std::ptrdiff_t nsrow = F.rowp[s + 1] - F.rowp[s];
    const int* r = F.rows.data() + F.rowp[s];
    const double* L = F.vals.data() + F.valp[s];
    double* Xs = X + static_cast<std::ptrdiff_t>(k1) * S;
    for (int j = (nscol - 1) / kTopBlock * kTopBlock; j >= 0; j -= kTopBlock) {
      const int B = std::min(kTopBlock, nscol - j);
      const std::ptrdiff_t first = j + B, chunks = (nsrow - first + kTopRows - 1) / kTopRows;
      steps.run(nsrow - first, top_grain(nsrow - first, threads), [&](long long b, long long e) {
        for (long long c = b; c < e; c += kTopRows)
          bwd(L, nsrow, j, B, r, X, partial + c / kTopRows * kTopBlock * S, first + c,
              first + std::min<long long>(c + kTopRows, e));
      });
      Vec<S> x[kTopBlock];
      for (int k = B - 1; k >= 0; --k) {
        const double* ck = L + static_cast<std::ptrdiff_t>(j + k) * nsrow;
        Vec<S> v = load<S>(Xs + (j + k) * S);
        for (std::ptrdiff_t c = 0; c < chunks; ++c) v -= load<S>(partial + (c * kTopBlock + k) * S);
        for (int q = k + 1; q < B; ++q) v -= ck[j + q] * x[q];
        x[k] = v * (1.0 / ck[j + k]);
        store<S>(Xs + (j + k) * S, x[k]);
      }
    }
  }
}

void top_w(int S, const CholeskyFactor& F, double* X, double* partial, double* ytop, Steps& steps, int threads) {
  switch (S) {
    case 1: return top_part<1>(F, X, partial, ytop, steps, threads);
    case 2: return top_part<2>(F, X, partial, ytop, steps, threads);
    case 4: return top_part<4>(F, X, partial, ytop, steps, threads);
    default: return top_part<8>(F, X, partial, ytop, steps, threads);
  }
}

template <int S>
void sweep_plain(const CholeskyFactor& F, const std::vector<int>* list, bool forward, double* X,
                 const int* rmap) {
  sweep_body<S>(F, list, forward, X, rmap);
}

#ifdef MBI_INTERP_X86
template <int S>
__attribute__((target("avx2,fma"))) void sweep_avx2(const CholeskyFactor& F, const std::vector<int>* list,
                                                    bool forward, double* X, const int* rmap) {
  sweep_body<S>(F, list, forward, X, rmap);
}

#endif

template <int S>
void sweep(const CholeskyFactor& F, const std::vector<int>* list, bool forward, double* X, const int* rmap) {
#ifdef MBI_INTERP_X86
  if (have_avx2_fma()) return sweep_avx2<S>(F, list, forward, X, rmap);
#endif
  sweep_plain<S>(F, list, forward, X, rmap);
}

void sweep_w(int S, const CholeskyFactor& F, const std::vector<int>* list, bool forward, double* X,
             const int* rmap) {
  switch (S) {
    case 1: return sweep<1>(F, list, forward, X, rmap);
    case 2: return sweep<2>(F, list, forward, X, rmap);
    case 4: return sweep<4>(F, list, forward, X, rmap);
    default: return sweep<8>(F, list, forward, X, rmap);
  }
}

}  // namespace

void CholeskyFactor::solve(double* B, int w) const {
  if (w < 1 || w > 8) throw Error("1 to 8 right-hand sides at a time");
  // padded width of the sweeps: 1, 2, 4 or 8 doubles a row
  const int S = w == 1 ? 1 : w == 2 ? 2 : w <= 4 ? 4 : 8;
  const std::ptrdiff_t nS = static_cast<std::ptrdiff_t>(n) * S;
  const bool grouped = bins > 1;
  // the top part's chunks of partial sums: as many as the tallest top supernode has
  std::ptrdiff_t tallest = 0;
  for (int s : top) tallest = std::max<std::ptrdiff_t>(tallest, rowp[s + 1] - rowp[s]);
  const std::ptrdiff_t partials = (tallest + kTopRows - 1) / kTopRows * kTopBlock * S;
  // scratch of the calling thread, kept between calls: X, then (grouped) one copy per group,
  // the partial sums and the triangle's solution
  thread_local std::vector<double> scratch;
  const size_t need = static_cast<size_t>(nS) * (grouped ? 1 + bins : 1) +
                      (grouped ? static_cast<size_t>(partials + kTopBlock * S) : 0);
  if (scratch.size() < need) scratch.resize(need);
  double* X = scratch.data();
  for (int k = 0; k < n; ++k) {
    double* xk = X + static_cast<std::ptrdiff_t>(k) * S;
    const double* bk = B + static_cast<std::ptrdiff_t>(perm[k]) * w;
    for (int c = 0; c < w; ++c) xk[c] = bk[c];
    for (int c = w; c < S; ++c) xk[c] = 0.0;
  }
  if (!grouped) {
    sweep_w(S, *this, nullptr, true, X, rows.data());
    sweep_w(S, *this, nullptr, false, X, rows.data());
  } else {
    // the groups' copies of the top part's rows start at zero
    for (int s : top)
      for (int g = 0; g < bins; ++g)
        std::fill(X + nS * (1 + g) + static_cast<std::ptrdiff_t>(super[s]) * S,
                  X + nS * (1 + g) + static_cast<std::ptrdiff_t>(super[s + 1]) * S, 0.0);
    double* partial = X + nS * (1 + bins);
    double* ytop = partial + partials;
    // One job on the library's threads: the groups' forward sweeps, the top part, the groups'
    // backward sweeps, each a step; the same arithmetic on one thread as on many.
    Steps steps;
    const std::thread::id caller = std::this_thread::get_id();
    const int threads = all_threads();
    run_shared(threads, [&] {
      if (std::this_thread::get_id() != caller) return steps.join();
      steps.run(bins, 1, [&](long long g0, long long g1) {
        for (long long g = g0; g < g1; ++g) sweep_w(S, *this, &groups[g], true, X, prow.data());
      });
      for (int s : top)
        for (std::ptrdiff_t e = static_cast<std::ptrdiff_t>(super[s]) * S; e < static_cast<std::ptrdiff_t>(super[s + 1]) * S; ++e)
          for (int g = 0; g < bins; ++g) X[e] += X[nS * (1 + g) + e];
      top_w(S, *this, X, partial, ytop, steps, threads);
      steps.run(bins, 1, [&](long long g0, long long g1) {
        for (long long g = g0; g < g1; ++g) sweep_w(S, *this, &groups[g], false, X, rows.data());
      });
      steps.close();
    });
  }
  for (int k = 0; k < n; ++k) {
    const double* xk = X + static_cast<std::ptrdiff_t>(k) * S;
    double* bk = B + static_cast<std::ptrdiff_t>(perm[k]) * w;
    for (int c = 0; c < w; ++c) bk[c] = xk[c];
  }
}

}  // namespace mbi::interp::detail
