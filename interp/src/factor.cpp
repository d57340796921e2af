// Sparse Cholesky factor (see factor.hpp).
#include "factor.hpp"

#include <mbi/error.hpp>

#include <Eigen/SparseCholesky>
#include <algorithm>
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

// Forward L y = b and backward L^T x = y over the supernodes; X holds S doubles a row (the
// right-hand sides, padded). Within a supernode the dense diagonal block is solved first, then
// the rows below are updated 4 columns at a time, so that each row of X is loaded and stored once
// per 4 columns of L.
template <int S>
__attribute__((always_inline)) inline void sweeps_body(const CholeskyFactor& F, double* X) {
  const int ns = static_cast<int>(F.super.size()) - 1;
  const int* rows = F.rows.data();
  const double* vals = F.vals.data();
  for (int s = 0; s < ns; ++s) {
    const int k1 = F.super[s], nscol = F.super[s + 1] - k1;
    const std::ptrdiff_t nsrow = F.rowp[s + 1] - F.rowp[s];
    const int* r = rows + F.rowp[s];
    const double* L = vals + F.valp[s];
    double* Xs = X + static_cast<std::ptrdiff_t>(k1) * S;
    for (int j = 0; j < nscol; ++j) {  // diagonal block
      const double* col = L + j * nsrow;
      double* xj = Xs + j * S;
      const double inv = 1.0 / col[j];
      for (int c = 0; c < S; ++c) xj[c] *= inv;
      for (int i = j + 1; i < nscol; ++i) {
        double* xi = Xs + i * S;
        for (int c = 0; c < S; ++c) xi[c] -= col[i] * xj[c];
      }
    }
    int j = 0;
    for (; j + 4 <= nscol; j += 4) {
      const double *c0 = L + j * nsrow, *c1 = c0 + nsrow, *c2 = c1 + nsrow, *c3 = c2 + nsrow;
      const double *x0 = Xs + j * S, *x1 = x0 + S, *x2 = x1 + S, *x3 = x2 + S;
      for (std::ptrdiff_t i = nscol; i < nsrow; ++i) {
        double* xi = X + static_cast<std::ptrdiff_t>(r[i]) * S;
        for (int c = 0; c < S; ++c) xi[c] -= c0[i] * x0[c] + c1[i] * x1[c] + c2[i] * x2[c] + c3[i] * x3[c];
      }
    }
    for (; j < nscol; ++j) {
      const double* c0 = L + j * nsrow;
      const double* x0 = Xs + j * S;
      for (std::ptrdiff_t i = nscol; i < nsrow; ++i) {
        double* xi = X + static_cast<std::ptrdiff_t>(r[i]) * S;
        for (int c = 0; c < S; ++c) xi[c] -= c0[i] * x0[c];
      }
    }
  }
  for (int s = ns - 1; s >= 0; --s) {
    const int k1 = F.super[s], nscol = F.super[s + 1] - k1;
    const std::ptrdiff_t nsrow = F.rowp[s + 1] - F.rowp[s];
    const int* r = rows + F.rowp[s];
    const double* L = vals + F.valp[s];
    double* Xs = X + static_cast<std::ptrdiff_t>(k1) * S;
    int j = 0;
    for (; j + 4 <= nscol; j += 4) {  // rows below: x_j -= sum_i L(i, j) x_i, 4 columns at once
      const double *c0 = L + j * nsrow, *c1 = c0 + nsrow, *c2 = c1 + nsrow, *c3 = c2 + nsrow;
      double a0[S] = {}, a1[S] = {}, a2[S] = {}, a3[S] = {};
      for (std::ptrdiff_t i = nscol; i < nsrow; ++i) {
        const double* xi = X + static_cast<std::ptrdiff_t>(r[i]) * S;
        for (int c = 0; c < S; ++c) {
          a0[c] += c0[i] * xi[c];
          a1[c] += c1[i] * xi[c];
          a2[c] += c2[i] * xi[c];
          a3[c] += c3[i] * xi[c];
        }
      }
      double* x0 = Xs + j * S;
      for (int c = 0; c < S; ++c) {
        x0[c] -= a0[c];
        x0[S + c] -= a1[c];
        x0[2 * S + c] -= a2[c];
        x0[3 * S + c] -= a3[c];
      }
    }
    for (; j < nscol; ++j) {
      const double* c0 = L + j * nsrow;
      double a0[S] = {};
      for (std::ptrdiff_t i = nscol; i < nsrow; ++i) {
        const double* xi = X + static_cast<std::ptrdiff_t>(r[i]) * S;
        for (int c = 0; c < S; ++c) a0[c] += c0[i] * xi[c];
      }
      for (int c = 0; c < S; ++c) Xs[j * S + c] -= a0[c];
    }
    for (int jj = nscol - 1; jj >= 0; --jj) {  // diagonal block
      const double* col = L + jj * nsrow;
      double* xj = Xs + jj * S;
      for (int i = jj + 1; i < nscol; ++i) {
        const double* xi = Xs + i * S;
        for (int c = 0; c < S; ++c) xj[c] -= col[i] * xi[c];
      }
      const double inv = 1.0 / col[jj];
      for (int c = 0; c < S; ++c) xj[c] *= inv;
    }
  }
}

template <int S>
void sweeps_plain(const CholeskyFactor& F, double* X) {
  sweeps_body<S>(F, X);
}

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define MBI_FACTOR_X86 1
template <int S>
__attribute__((target("avx2,fma"))) void sweeps_avx2(const CholeskyFactor& F, double* X) {
  sweeps_body<S>(F, X);
}

bool have_avx2() {
  static const bool ok = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  return ok;
}
#endif

template <int S>
void sweeps(const CholeskyFactor& F, double* X) {
#ifdef MBI_FACTOR_X86
  if (have_avx2()) return sweeps_avx2<S>(F, X);
#endif
  sweeps_plain<S>(F, X);
}

}  // namespace

void CholeskyFactor::solve(double* B, int w, double* work) const {
  if (w < 1 || w > 8) throw Error("CholeskyFactor::solve: 1 to 8 right-hand sides at a time");
  // padded width of the sweeps: 1, 2, 4 or 8 doubles a row
  const int S = w == 1 ? 1 : w == 2 ? 2 : w <= 4 ? 4 : 8;
  std::vector<double> pad;
  double* Xw = work;
  if (S != w) {
    pad.assign(static_cast<size_t>(n) * S, 0.0);
    Xw = pad.data();
  }
  for (int k = 0; k < n; ++k)
    for (int c = 0; c < w; ++c)
      Xw[static_cast<std::ptrdiff_t>(k) * S + c] = B[static_cast<std::ptrdiff_t>(perm[k]) * w + c];
  switch (S) {
    case 1: sweeps<1>(*this, Xw); break;
    case 2: sweeps<2>(*this, Xw); break;
    case 4: sweeps<4>(*this, Xw); break;
    default: sweeps<8>(*this, Xw); break;
  }
  for (int k = 0; k < n; ++k)
    for (int c = 0; c < w; ++c)
      B[static_cast<std::ptrdiff_t>(perm[k]) * w + c] = Xw[static_cast<std::ptrdiff_t>(k) * S + c];
}

bool cholmod_available() {
#ifdef MBI_HAVE_CHOLMOD
  return true;
#else
  return false;
#endif
}

namespace {

CholeskyFactor eigen_factor(const Eigen::SparseMatrix<double>& A, const char* who) {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(A);
  if (llt.info() != Eigen::Success)
    throw Error(std::string(who) + ": Cholesky factorisation failed: the reduced system is not positive definite");
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
      throw Error(std::string(who) + ": unexpected layout of Eigen's Cholesky factor");
  return F;
}

#ifdef MBI_HAVE_CHOLMOD
CholeskyFactor factor_with_cholmod(const Eigen::SparseMatrix<double>& A, const char* who) {
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
  bool ok = L != nullptr && c.status == CHOLMOD_OK;
  if (ok) ok = cholmod_factorize(&As, L, &c) && c.status == CHOLMOD_OK && L->minor == L->n;
  if (!ok || !L->is_super || L->itype != CHOLMOD_INT) {
    if (L) cholmod_free_factor(&L, &c);
    cholmod_finish(&c);
    throw Error(std::string(who) + ": Cholesky factorisation (CHOLMOD) failed: the reduced system is not positive definite");
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

CholeskyFactor cholesky(const Eigen::SparseMatrix<double>& A, bool use_cholmod, const char* who) {
  if (use_cholmod) {
#ifdef MBI_HAVE_CHOLMOD
    return factor_with_cholmod(A, who);
#else
    throw Error(std::string(who) + ": this build has no CHOLMOD (configure with MBI_WITH_CHOLMOD=ON and libsuitesparse-dev)");
#endif
  }
  return eigen_factor(A, who);
}

}  // namespace mbi::interp::detail
