// Sparse Cholesky factor (see factor.hpp).
#include "linalg/factor.hpp"

#include "runtime/threads.hpp"

#include <mbi/interp/threads.hpp>

#include <mbi/error.hpp>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <new>
#include <optional>
#include <string>

#ifdef MBI_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

namespace mbi::interp::detail {

void FactorValues::allocate(std::size_t n) {
  p_.reset();
  n_ = 0;
  auto* p = static_cast<double*>(std::malloc(std::max<std::size_t>(n, 1) * sizeof(double)));
  if (p == nullptr) throw std::bad_alloc();
  p_ = std::unique_ptr<double, void (*)(void*)>(p, &std::free);
  n_ = n;
}

void FactorValues::adopt(double* p, std::size_t n, void (*release)(void*)) {
  p_ = std::unique_ptr<double, void (*)(void*)>(p, release);
  n_ = n;
}

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

std::size_t CholeskyFactor::index_bytes() const {
  return (rows.size() + super.size()) * sizeof(int) + (rowp.size() + valp.size()) * sizeof(std::ptrdiff_t);
}

namespace {

// The supernodal elimination tree: parent[s] (-1: a root) holds the first row below s's diagonal
// block; col_super maps a column to its supernode. False when a parent does not come after its
// child (not a tree in topological order: the sweeps then stay serial).
bool supernode_tree(const CholeskyFactor& F, std::vector<int>& col_super, std::vector<int>& parent) {
  const int ns = static_cast<int>(F.super.size()) - 1;
  col_super.assign(static_cast<size_t>(F.n), 0);
  parent.assign(static_cast<size_t>(ns), -1);
  for (int s = 0; s < ns; ++s)
    for (int k = F.super[s]; k < F.super[s + 1]; ++k) col_super[k] = s;
  for (int s = 0; s < ns; ++s) {
    const int nscol = F.super[s + 1] - F.super[s];
    int first = F.n;
    for (std::ptrdiff_t i = F.rowp[s] + nscol; i < F.rowp[s + 1]; ++i) first = std::min(first, F.rows[i]);
    if (first < F.n) {
      parent[s] = col_super[first];
      if (parent[s] <= s) return false;
    }
  }
  return true;
}

// Candidate subtrees packed into n_groups bins, largest first onto the least loaded; returns the
// heaviest bin's load, bin_of[i] the bin of candidate c[i].
double pack(const std::vector<int>& c, const std::vector<double>& work, int n_groups, std::vector<int>& bin_of) {
  std::vector<int> order(c.size());
  for (size_t i = 0; i < c.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return work[c[a]] > work[c[b]]; });
  std::vector<double> load(n_groups, 0.0);
  bin_of.assign(c.size(), 0);
  for (int i : order) {
    const int b = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
    bin_of[i] = b;
    load[b] += work[c[i]];
  }
  return *std::max_element(load.begin(), load.end());
}

// A split of the tree: the subtrees run by the groups (`cand`, each in group bin[i]) and the
// supernodes above them (`top`); cost = the top part's work + the heaviest group's.
struct Split {
  std::vector<int> cand, bin;
  std::vector<char> top;
  double cost = 0;
};

// Splits the largest candidate subtree into its children until the groups balance, and keeps the
// split with the least critical path. work[s]: entries of L in s's subtree. (A chain of single
// columns above the first branch, as Eigen's simplicial factor has, takes one split a column; the
// top part only grows, so once it costs more than the best split no later one can be better.)
Split best_split(const std::vector<int>& parent, const std::vector<std::vector<int>>& children,
                 const std::vector<double>& work, int n_groups) {
  const int ns = static_cast<int>(parent.size());
  std::vector<int> cand;
  for (int s = 0; s < ns; ++s)
    if (parent[s] < 0) cand.push_back(s);
  std::vector<char> is_top(ns, 0);
  double top_work = 0;
  Split best;
  for (int s : cand) best.cost += work[s];  // serial
  for (int iter = 0; iter < 100000 && !cand.empty() && top_work < best.cost; ++iter) {
    std::vector<int> bin_of;
    const double cost = top_work + pack(cand, work, n_groups, bin_of);
    if (cost < best.cost) best = {cand, bin_of, is_top, cost};
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
  return best;
}

}  // namespace

void CholeskyFactor::schedule(int n_groups, std::ptrdiff_t min_nonzeros) {
  bins = 1;
  groups.clear();
  top.clear();
  prow.clear();
  const int ns = static_cast<int>(super.size()) - 1;
  if (n_groups < 2 || ns < 2 || nonzeros() < min_nonzeros) return;
  n_groups = std::min(n_groups, 8);
  std::vector<int> col_super, parent;
  if (!supernode_tree(*this, col_super, parent)) return;
  std::vector<std::vector<int>> children(ns);
  std::vector<double> work(ns);  // entries of L in the subtree
  double total = 0;
  for (int s = 0; s < ns; ++s) {
    const double nscol = super[s + 1] - super[s];
    work[s] += nscol * static_cast<double>(rowp[s + 1] - rowp[s]);
    if (parent[s] >= 0) {
      children[parent[s]].push_back(s);
      work[parent[s]] += work[s];
    }
  }
  for (int s = 0; s < ns; ++s)
    if (parent[s] < 0) total += work[s];
  const Split best = best_split(parent, children, work, n_groups);
  if (best.cand.empty() || best.cost > 0.8 * total) return;  // no useful split
  std::vector<int> owner(ns, -1);
  for (size_t i = 0; i < best.cand.size(); ++i) owner[best.cand[i]] = best.bin[i];
  for (int s = ns - 1; s >= 0; --s) {
    if (best.top[s]) owner[s] = -1;
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
  groups.assign(n_groups, {});
  for (int s = 0; s < ns; ++s) (owner[s] < 0 ? top : groups[owner[s]]).push_back(s);
  bins = n_groups;
}

std::mutex& ordering_mutex() {
  static std::mutex m;
  return m;
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
  // Eigen's own L, not a copy (diagonal first in each column): the copy below is the only one
  const Eigen::SparseMatrix<double>& L = llt.matrixL().nestedExpression();
  F.perm.resize(F.n);
  // Eigen: y = P b with y[P.indices()[i]] = b[i]; ours: y[k] = b[perm[k]]
  for (int i = 0; i < F.n; ++i) F.perm[llt.permutationP().indices()[i]] = i;
  F.super.resize(F.n + 1);
  F.rowp.resize(F.n + 1);
  F.valp.resize(F.n + 1);
  F.rows.resize(L.nonZeros());
  F.vals.allocate(static_cast<std::size_t>(L.nonZeros()));
  for (int j = 0; j <= F.n; ++j) {
    F.super[j] = j;
    F.rowp[j] = F.valp[j] = L.outerIndexPtr()[j];
  }
  for (std::ptrdiff_t k = 0; k < L.nonZeros(); ++k) {
    F.rows[k] = L.innerIndexPtr()[k];
    F.vals.data()[k] = L.valuePtr()[k];
  }
  for (int j = 0; j < F.n; ++j)
    if (F.rowp[j] == F.rowp[j + 1] || F.rows[F.rowp[j]] != j)
      throw Error("unexpected layout of Eigen's Cholesky factor");
  return F;
}

#ifdef MBI_HAVE_CHOLMOD
// Flops above which the factorization runs BLAS on the library's threads (about 10,000 control
// vertices and up; below it one thread is as fast, docs/performance.md "Threads").
constexpr double kParallelFactorFlops = 4e9;

// L's values after they changed hands: freed as CHOLMOD frees its memory
void release_cholmod(void* p) {
  cholmod_common c;
  cholmod_start(&c);
  cholmod_free(0, sizeof(double), p, &c);
  cholmod_finish(&c);
}

CholeskyFactor factor_with_cholmod(const Eigen::SparseMatrix<double>& A) {
  cholmod_common c;
  cholmod_start(&c);
  c.supernodal = CHOLMOD_SUPERNODAL;
  c.print = 0;
  // Nested dissection (METIS) gives less fill than AMD on these volume meshes, and CHOLMOD keeps
  // the better of the two; below kMetisMinUnknowns METIS's ordering costs more time than it saves.
  c.nmethods = A.rows() < kMetisMinUnknowns ? 1 : 2;
  c.method[0].ordering = CHOLMOD_AMD;
  c.method[1].ordering = CHOLMOD_METIS;
  c.postorder = 1;
  Eigen::SparseMatrix<double> Ac = A;  // viewAsCholmod needs a mutable, compressed matrix
  Ac.makeCompressed();
  cholmod_sparse As = Eigen::viewAsCholmod(Eigen::Ref<Eigen::SparseMatrix<double>>(Ac));
  As.stype = -1;  // symmetric: CHOLMOD reads the lower triangle
  // serial: BLAS's and CHOLMOD's own threads would spin for milliseconds after it (threads.hpp)
  std::optional<SerialForeignPools> pools(std::in_place);
  std::unique_lock<std::mutex> one_at_a_time(ordering_mutex());
  cholmod_factor* L = cholmod_analyze(&As, &c);
  one_at_a_time.unlock();
  const bool analyzed = L != nullptr && c.status >= CHOLMOD_OK;
  // a large factorization gains more from BLAS's threads than they cost spinning after it
  if (analyzed && c.fl > kParallelFactorFlops) pools.emplace(interp::threads());
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
  // the values change hands: no second copy
  F.vals.adopt(static_cast<double*>(L->x), static_cast<std::size_t>(px[ns]), &release_cholmod);
  L->x = nullptr;
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
  F.schedule(kGroups);
  return F;
}

}  // namespace mbi::interp::detail
