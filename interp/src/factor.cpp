// Sparse Cholesky factor (see factor.hpp).
#include "factor.hpp"

#include "cpu.hpp"
#include "threads.hpp"

#include <mbi/error.hpp>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cstring>
#include <string>

#ifdef MBI_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

namespace mbi::interp::detail {

std::ptrdiff_t CholeskyFactor::nonzeros() const {
  std::ptrdiff_t nz = 0;
  for (size_t s = 0; s + 1 < super.size(); ++s) {
    const std::ptrdiff_t nscol = super[s + 1] - super[s];
    const std::ptrdiff_t nsrow = rowp[s + 1] - rowp[s];
    nz += nscol * nsrow - nscol * (nscol - 1) / 2;  // the diagonal block's upper part is not L
  }
  return nz;
}

std::size_t CholeskyFactor::bytes() const {
  return perm.size() * sizeof(int) + super.size() * sizeof(int) +
         (rowp.size() + valp.size()) * sizeof(std::ptrdiff_t) + rows.size() * sizeof(int) +
         vals.size() * sizeof(double);
}

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

// Forward L y = b and backward L^T x = y, one supernode at a time, in panels of 4 columns; X
// holds S doubles a row (the right-hand sides, padded). A panel's 4 x 4 triangle is solved in
// registers, then one pass over every row below it (the rest of the diagonal block and the rows
// below the supernode alike: row i of the supernode is X's row rmap[i]) applies its 4 columns:
// each such row of X is loaded and stored once per panel, and the backward sums run in 4
// independent accumulators. `rmap` is F.rows, or F.prow for a group of the threaded forward
// sweep (the supernode's own columns come first in both).
constexpr int kPanel = 4;  // columns of a panel (wider panels ran slower)

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
  int j = 0;
  for (; j + kPanel <= nscol; j += kPanel) forward_panel<S, kPanel>(L, nsrow, j, r, X, Xs);
  switch (nscol - j) {
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
  const int full = nscol / kPanel * kPanel;  // the same panels as forward_super, last first
  switch (nscol - full) {
    case 3: backward_panel<S, 3>(L, nsrow, full, r, X, Xs); break;
    case 2: backward_panel<S, 2>(L, nsrow, full, r, X, Xs); break;
    case 1: backward_panel<S, 1>(L, nsrow, full, r, X, Xs); break;
    default: break;
  }
  for (int j = full - kPanel; j >= 0; j -= kPanel) backward_panel<S, kPanel>(L, nsrow, j, r, X, Xs);
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

// The top part of a threaded solve, inside the parallel region, on every thread of the team
// (t of T): supernodes of at least F.top_split entries are shared out, in blocks of 16 columns
// (forward: each thread solves the block's triangle itself and updates its share of the rows
// below; backward: each thread sums over its share, one thread finishes the block); smaller ones
// run on thread 0. `partial`: T x 16 x S doubles.
constexpr int kTopBlock = 16;

template <int S>
__attribute__((always_inline)) inline void top_body(const CholeskyFactor& F, double* X, double* partial,
                                                    int t, int T) {
  const int* rows = F.rows.data();
  auto big = [&](int s) {
    return static_cast<std::ptrdiff_t>(F.super[s + 1] - F.super[s]) * (F.rowp[s + 1] - F.rowp[s]) >= F.top_split;
  };
  auto share = [&](std::ptrdiff_t a, std::ptrdiff_t b, std::ptrdiff_t& lo, std::ptrdiff_t& hi) {
    lo = a + (b - a) * t / T;
    hi = a + (b - a) * (t + 1) / T;
  };
  for (int s : F.top) {
    if (!big(s)) {
      if (t == 0) forward_super<S>(F, s, X, rows);
      continue;
    }
    MBI_INTERP_OMP("omp barrier")
    const int k1 = F.super[s], nscol = F.super[s + 1] - k1;
    const std::ptrdiff_t nsrow = F.rowp[s + 1] - F.rowp[s];
    const int* r = rows + F.rowp[s];
    const double* L = F.vals.data() + F.valp[s];
    double* Xs = X + static_cast<std::ptrdiff_t>(k1) * S;
    Vec<S> y[kTopBlock];
    for (int j = 0; j < nscol; j += kTopBlock) {
      const int B = std::min(kTopBlock, nscol - j);
      for (int k = 0; k < B; ++k) {  // the block's triangle, on every thread (same values)
        const double* ck = L + static_cast<std::ptrdiff_t>(j + k) * nsrow;
        Vec<S> v = load<S>(Xs + (j + k) * S);
        for (int q = 0; q < k; ++q) v -= L[static_cast<std::ptrdiff_t>(j + q) * nsrow + j + k] * y[q];
        y[k] = v * (1.0 / ck[j + k]);
      }
      std::ptrdiff_t lo, hi;
      share(j + B, nsrow, lo, hi);
      for (int k0 = 0; k0 < B; k0 += 4) {
        const int w = std::min(4, B - k0);
        const double* c0 = L + static_cast<std::ptrdiff_t>(j + k0) * nsrow;
        const double* c1 = c0 + nsrow;
        const double* c2 = c1 + nsrow;
        const double* c3 = c2 + nsrow;
        const Vec<S> y0 = y[k0], y1 = w > 1 ? y[k0 + 1] : Vec<S>{}, y2 = w > 2 ? y[k0 + 2] : Vec<S>{},
                     y3 = w > 3 ? y[k0 + 3] : Vec<S>{};
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
      MBI_INTERP_OMP("omp barrier")
      // every thread has read the block's rows; the next phases read and write only rows after it
      if (t == 0)
        for (int k = 0; k < B; ++k) store<S>(Xs + (j + k) * S, y[k]);
    }
    MBI_INTERP_OMP("omp barrier")
  }
  MBI_INTERP_OMP("omp barrier")
  for (auto it = F.top.rbegin(); it != F.top.rend(); ++it) {
    const int s = *it;
    if (!big(s)) {
      if (t == 0) backward_super<S>(F, s, X);
      continue;
    }
    MBI_INTERP_OMP("omp barrier")
    const int k1 = F.super[s], nscol = F.super[s + 1] - k1;
    const std::ptrdiff_t nsrow = F.rowp[s + 1] - F.rowp[s];
    const int* r = rows + F.rowp[s];
    const double* L = F.vals.data() + F.valp[s];
    double* Xs = X + static_cast<std::ptrdiff_t>(k1) * S;
    for (int j = (nscol - 1) / kTopBlock * kTopBlock; j >= 0; j -= kTopBlock) {
      const int B = std::min(kTopBlock, nscol - j);
      std::ptrdiff_t lo, hi;
      share(j + B, nsrow, lo, hi);
      double* mine = partial + static_cast<std::ptrdiff_t>(t) * kTopBlock * S;
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
        for (int k = 0; k < w; ++k) store<S>(mine + (k0 + k) * S, a[k]);
      }
      MBI_INTERP_OMP("omp barrier")
      if (t == 0) {
        Vec<S> x[kTopBlock];
        for (int k = B - 1; k >= 0; --k) {
          const double* ck = L + static_cast<std::ptrdiff_t>(j + k) * nsrow;
          Vec<S> v = load<S>(Xs + (j + k) * S);
          for (int u = 0; u < T; ++u) v -= load<S>(partial + (static_cast<std::ptrdiff_t>(u) * kTopBlock + k) * S);
          for (int q = k + 1; q < B; ++q) v -= ck[j + q] * x[q];
          x[k] = v * (1.0 / ck[j + k]);
          store<S>(Xs + (j + k) * S, x[k]);
        }
      }
      MBI_INTERP_OMP("omp barrier")
    }
  }
}

template <int S>
void top_plain(const CholeskyFactor& F, double* X, double* partial, int t, int T) {
  top_body<S>(F, X, partial, t, T);
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

template <int S>
__attribute__((target("avx2,fma"))) void top_avx2(const CholeskyFactor& F, double* X, double* partial, int t, int T) {
  top_body<S>(F, X, partial, t, T);
}
#endif

void top_w(int S, const CholeskyFactor& F, double* X, double* partial, int t, int T) {
#ifdef MBI_INTERP_X86
  if (have_avx2_fma()) {
    switch (S) {
      case 1: return top_avx2<1>(F, X, partial, t, T);
      case 2: return top_avx2<2>(F, X, partial, t, T);
      case 4: return top_avx2<4>(F, X, partial, t, T);
      default: return top_avx2<8>(F, X, partial, t, T);
    }
  }
#endif
  switch (S) {
    case 1: return top_plain<1>(F, X, partial, t, T);
    case 2: return top_plain<2>(F, X, partial, t, T);
    case 4: return top_plain<4>(F, X, partial, t, T);
    default: return top_plain<8>(F, X, partial, t, T);
  }
}

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

void CholeskyFactor::schedule(int threads, std::ptrdiff_t min_nonzeros) {
  bins = 1;
  groups.clear();
  top.clear();
  prow.clear();
  const int ns = static_cast<int>(super.size()) - 1;
  if (threads < 2 || ns < 2 || nonzeros() < min_nonzeros) return;
  threads = std::min(threads, 8);
  // supernodal elimination tree: the parent holds the first row below the diagonal block
  std::vector<int> col_super(n), parent(ns, -1);
  for (int s = 0; s < ns; ++s)
    for (int k = super[s]; k < super[s + 1]; ++k) col_super[k] = s;
  for (int s = 0; s < ns; ++s) {
    const int nscol = super[s + 1] - super[s];
    int first = n;
    for (std::ptrdiff_t i = rowp[s] + nscol; i < rowp[s + 1]; ++i) first = std::min(first, rows[i]);
    if (first < n) {
      parent[s] = col_super[first];
      if (parent[s] <= s) return;  // not a tree in topological order: stay serial
    }
  }
  std::vector<std::vector<int>> children(ns);
  std::vector<double> work(ns);  // entries of L in the subtree
  for (int s = 0; s < ns; ++s) {
    const double nscol = super[s + 1] - super[s];
    work[s] += nscol * static_cast<double>(rowp[s + 1] - rowp[s]);
    if (parent[s] >= 0) {
      children[parent[s]].push_back(s);
      work[parent[s]] += work[s];
    }
  }
  // Split the largest candidate subtree into its children until the groups balance; keep the
  // split with the least critical path (top part + heaviest group).
  std::vector<int> cand;
  for (int s = 0; s < ns; ++s)
    if (parent[s] < 0) cand.push_back(s);
  std::vector<char> is_top(ns, 0);
  double top_work = 0, best_cost = 0;
  for (int s : cand) best_cost += work[s];  // serial
  std::vector<int> best_cand;
  std::vector<char> best_top;
  std::vector<int> best_bin;
  auto pack = [&](const std::vector<int>& c, std::vector<int>& bin_of) {  // largest first
    std::vector<int> order(c.size());
    for (size_t i = 0; i < c.size(); ++i) order[i] = static_cast<int>(i);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return work[c[a]] > work[c[b]]; });
    std::vector<double> load(threads, 0.0);
    bin_of.assign(c.size(), 0);
    for (int i : order) {
      const int b = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
      bin_of[i] = b;
      load[b] += work[c[i]];
    }
    return *std::max_element(load.begin(), load.end());
  };
  // (a chain of single columns above the first branch, as Eigen's simplicial factor has, takes
  // one split a column; the top part only grows, so once it costs more than the best split no
  // later one can be better)
  for (int iter = 0; iter < 100000 && !cand.empty() && top_work < best_cost; ++iter) {
    std::vector<int> bin_of;
    const double cost = top_work + pack(cand, bin_of);
    if (cost < best_cost) {
      best_cost = cost;
      best_cand = cand;
      best_top = is_top;
      best_bin = bin_of;
    }
    auto big = std::max_element(cand.begin(), cand.end(), [&](int a, int b) { return work[a] < work[b]; });
    const int s = *big;
    cand.erase(big);
    is_top[s] = 1;
    top_work += work[s];
    for (int c : children[s]) {
      top_work -= work[c];
      cand.push_back(c);
    }
  }
  double total = 0;
  for (int s = 0; s < ns; ++s)
    if (parent[s] < 0) total += work[s];
  if (best_cand.empty() || best_cost > 0.8 * total) return;  // no useful split
  std::vector<int> owner(ns, -1);
  for (size_t i = 0; i < best_cand.size(); ++i) owner[best_cand[i]] = best_bin[i];
  for (int s = ns - 1; s >= 0; --s) {
    if (best_top[s]) owner[s] = -1;
    else if (owner[s] < 0 && parent[s] >= 0) owner[s] = owner[parent[s]];
  }
  prow = rows;
  for (int s = 0; s < ns; ++s) {
    if (owner[s] < 0) continue;
    for (std::ptrdiff_t i = rowp[s] + (super[s + 1] - super[s]); i < rowp[s + 1]; ++i) {
      const int o = owner[col_super[rows[i]]];
      if (o == owner[s]) continue;
      if (o != -1) return prow.clear();  // a row of another group: not a tree split, stay serial
      prow[i] = n * (1 + owner[s]) + rows[i];
    }
  }
  groups.assign(threads, {});
  for (int s = 0; s < ns; ++s) (owner[s] < 0 ? top : groups[owner[s]]).push_back(s);
  bins = threads;
}

void CholeskyFactor::solve(double* B, int w) const {
  if (w < 1 || w > 8) throw Error("1 to 8 right-hand sides at a time");
  // padded width of the sweeps: 1, 2, 4 or 8 doubles a row
  const int S = w == 1 ? 1 : w == 2 ? 2 : w <= 4 ? 4 : 8;
  const std::ptrdiff_t nS = static_cast<std::ptrdiff_t>(n) * S;
  const bool threaded = bins > 1 && omp_threads(bins, 1) > 1;
  // scratch of the calling thread, kept between calls: X, then one copy per group (threaded)
  thread_local std::vector<double> scratch;
  const size_t need = static_cast<size_t>(nS) * (threaded ? 1 + bins : 1) +
                     (threaded ? static_cast<size_t>(omp_threads(bins, 1)) * kTopBlock * S : 0);
  if (scratch.size() < need) scratch.resize(need);
  double* X = scratch.data();
  for (int k = 0; k < n; ++k) {
    double* xk = X + static_cast<std::ptrdiff_t>(k) * S;
    const double* bk = B + static_cast<std::ptrdiff_t>(perm[k]) * w;
    for (int c = 0; c < w; ++c) xk[c] = bk[c];
    for (int c = w; c < S; ++c) xk[c] = 0.0;
  }
  if (!threaded) {
    sweep_w(S, *this, nullptr, true, X, rows.data());
    sweep_w(S, *this, nullptr, false, X, rows.data());
  } else {
    // the groups' copies of the top part's rows start at zero
    for (int s : top)
      for (int g = 0; g < bins; ++g)
        std::fill(X + nS * (1 + g) + static_cast<std::ptrdiff_t>(super[s]) * S,
                  X + nS * (1 + g) + static_cast<std::ptrdiff_t>(super[s + 1]) * S, 0.0);
    const int nt = omp_threads(bins, 1);
    MBI_INTERP_OMP("omp parallel num_threads(nt)")
    {
      int t = 0, T = 1;
      omp_team(t, T);
      for (int g = t; g < bins; g += T) sweep_w(S, *this, &groups[g], true, X, prow.data());
    }
    for (int s : top)
      for (std::ptrdiff_t e = static_cast<std::ptrdiff_t>(super[s]) * S; e < static_cast<std::ptrdiff_t>(super[s + 1]) * S; ++e)
        for (int g = 0; g < bins; ++g) X[e] += X[nS * (1 + g) + e];
    // the top part: its large supernodes shared out between the threads
    double* partial = X + nS * (1 + bins);
    MBI_INTERP_OMP("omp parallel num_threads(nt)")
    {
      int t = 0, T = 1;
      omp_team(t, T);
      top_w(S, *this, X, partial, t, T);
    }
    MBI_INTERP_OMP("omp parallel num_threads(nt)")
    {
      int t = 0, T = 1;
      omp_team(t, T);
      for (int g = t; g < bins; g += T) sweep_w(S, *this, &groups[g], false, X, rows.data());
    }
    (void)nt;
  }
  for (int k = 0; k < n; ++k) {
    const double* xk = X + static_cast<std::ptrdiff_t>(k) * S;
    double* bk = B + static_cast<std::ptrdiff_t>(perm[k]) * w;
    for (int c = 0; c < w; ++c) bk[c] = xk[c];
  }
}

bool cholmod_available() {
#ifdef MBI_HAVE_CHOLMOD
  return true;
#else
  return false;
#endif
}

namespace {

CholeskyFactor eigen_factor(const Eigen::SparseMatrix<double>& A) {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(A);
  if (llt.info() != Eigen::Success)
    throw Error("Cholesky factorisation failed: the reduced system is not positive definite");
  CholeskyFactor F;
  F.method = "Eigen SimplicialLLT (AMD)";
  F.n = static_cast<int>(A.rows());
  const Eigen::SparseMatrix<double> L = llt.matrixL();  // diagonal first in each column
  F.perm.resize(F.n);
  // Eigen: y = P b with y[P.indices()[i]] = b[i]; ours: y[k] = b[perm[k]]
  for (int i = 0; i < F.n; ++i) F.perm[llt.permutationP().indices()[i]] = i;
  F.super.resize(F.n + 1);
  F.rowp.resize(F.n + 1);
  F.valp.resize(F.n + 1);
  F.rows.resize(L.nonZeros());
  F.vals.resize(L.nonZeros());
  for (int j = 0; j <= F.n; ++j) {
    F.super[j] = j;
    F.rowp[j] = F.valp[j] = L.outerIndexPtr()[j];
  }
  for (std::ptrdiff_t k = 0; k < L.nonZeros(); ++k) {
    F.rows[k] = L.innerIndexPtr()[k];
    F.vals[k] = L.valuePtr()[k];
  }
  for (int j = 0; j < F.n; ++j)
    if (F.rowp[j] == F.rowp[j + 1] || F.rows[F.rowp[j]] != j)
      throw Error("unexpected layout of Eigen's Cholesky factor");
  return F;
}

#ifdef MBI_HAVE_CHOLMOD
CholeskyFactor factor_with_cholmod(const Eigen::SparseMatrix<double>& A) {
  cholmod_common c;
  cholmod_start(&c);
  c.supernodal = CHOLMOD_SUPERNODAL;
  c.print = 0;
  // Nested dissection (METIS) gives far less fill than AMD on these volume meshes; CHOLMOD
  // keeps the better of the two.
  c.nmethods = 2;
  c.method[0].ordering = CHOLMOD_AMD;
  c.method[1].ordering = CHOLMOD_METIS;
  c.postorder = 1;
  Eigen::SparseMatrix<double> Ac = A;  // viewAsCholmod needs a mutable, compressed matrix
  Ac.makeCompressed();
  cholmod_sparse As = Eigen::viewAsCholmod(Eigen::Ref<Eigen::SparseMatrix<double>>(Ac));
  As.stype = -1;  // symmetric: CHOLMOD reads the lower triangle
  cholmod_factor* L = cholmod_analyze(&As, &c);
  const bool analyzed = L != nullptr && c.status >= CHOLMOD_OK;
  const bool factored = analyzed && cholmod_factorize(&As, L, &c) && c.status >= CHOLMOD_OK;
  std::string why;
  if (!analyzed || !factored)  // an error of CHOLMOD's own (out of memory, too large, ...)
    why = "CHOLMOD status " + std::to_string(c.status) +
          (c.status == CHOLMOD_OUT_OF_MEMORY ? " (out of memory)" : c.status == CHOLMOD_TOO_LARGE ? " (too large)" : "");
  else if (c.status == CHOLMOD_NOT_POSDEF || L->minor < L->n)
    why = "the reduced system is not positive definite";
  else if (!L->is_super || L->itype != CHOLMOD_INT)
    why = "unexpected factor layout";
  if (!why.empty()) {
    if (L) cholmod_free_factor(&L, &c);
    cholmod_finish(&c);
    throw Error("Cholesky factorisation (CHOLMOD) failed: " + why);
  }
  CholeskyFactor F;
  F.method = L->ordering == CHOLMOD_METIS ? "CHOLMOD supernodal (METIS)" : "CHOLMOD supernodal (AMD)";
  F.n = static_cast<int>(L->n);
  const int* perm = static_cast<const int*>(L->Perm);
  F.perm.assign(perm, perm + F.n);
  const size_t ns = L->nsuper;
  const int* super = static_cast<const int*>(L->super);
  const int* pi = static_cast<const int*>(L->pi);
  const int* px = static_cast<const int*>(L->px);
  F.super.assign(super, super + ns + 1);
  F.rowp.assign(pi, pi + ns + 1);
  F.valp.assign(px, px + ns + 1);
  const int* srows = static_cast<const int*>(L->s);
  F.rows.assign(srows, srows + pi[ns]);
  const double* x = static_cast<const double*>(L->x);
  F.vals.assign(x, x + px[ns]);
  cholmod_free_factor(&L, &c);
  cholmod_finish(&c);
  return F;
}
#endif

}  // namespace

CholeskyFactor cholesky(const Eigen::SparseMatrix<double>& A, bool use_cholmod) {
  CholeskyFactor F;
  if (use_cholmod) {
#ifdef MBI_HAVE_CHOLMOD
    F = factor_with_cholmod(A);
#else
    throw Error("this build has no CHOLMOD (configure with MBI_WITH_CHOLMOD=ON and libsuitesparse-dev)");
#endif
  } else {
    F = eigen_factor(A);
  }
  // the sweeps rely on it: each supernode's first rows are its own columns, in order
  for (size_t q = 0; q + 1 < F.super.size(); ++q)
    for (int k = F.super[q]; k < F.super[q + 1]; ++k)
      if (F.rows[F.rowp[q] + (k - F.super[q])] != k)
        throw Error("unexpected layout of the Cholesky factor (supernode " +
                    std::to_string(q) + ")");
  F.schedule(omp_threads(1LL << 30, 1));
  return F;
}

}  // namespace mbi::interp::detail
