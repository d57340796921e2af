#pragma once
// Sparse Cholesky factor of the modified-BI m-block (internal): P A P^T = L L^T, computed by
// Eigen's SimplicialLLT (always there) or CHOLMOD's supernodal factorization (when the build has
// it), and stored one way: by supernodes (a simplicial factor is one column a supernode). The
// per-frame solve then runs our own triangular sweeps over all right-hand sides at once (the d
// components of M share the matrix), reading the factor once per sweep instead of once per
// component as Eigen's solve does.
#include <Eigen/SparseCore>

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <vector>

namespace mbi::interp::detail {

/// The values of L: memory the factor owns, either its own (Eigen's path) or CHOLMOD's, adopted
/// without a copy (a copy would double the precompute's peak memory for a moment).
class FactorValues {
 public:
  /// n doubles of its own, uninitialised; std::bad_alloc when they cannot be had.
  void allocate(std::size_t n);
  /// Takes p (n doubles), released by `release` when the factor goes.
  void adopt(double* p, std::size_t n, void (*release)(void*));
  double* data() { return p_.get(); }
  const double* data() const { return p_.get(); }
  std::size_t size() const { return n_; }

 private:
  std::unique_ptr<double, void (*)(void*)> p_{nullptr, &std::free};
  std::size_t n_ = 0;
};

struct CholeskyFactor {
  int n = 0;
  std::vector<int> perm;             ///< (P b)[k] = b[perm[k]]
  std::vector<int> super;            ///< nsuper + 1: first column of each supernode
  std::vector<std::ptrdiff_t> rowp;  ///< nsuper + 1: supernode s's rows are rows[rowp[s] .. rowp[s+1])
  std::vector<std::ptrdiff_t> valp;  ///< nsuper + 1: its nsrow x nscol column-major block in vals
  std::vector<int> rows;             ///< first the supernode's own columns, then the rows below
  FactorValues vals;
  const char* method = "";           ///< "Eigen SimplicialLLT (AMD)" or "CHOLMOD supernodal (...)"

  // Schedule of the sweeps on several threads (schedule()): disjoint subtrees of the supernodal
  // elimination tree are put into `bins` groups of about equal work, handed to the threads as
  // they come; the supernodes above them (`top`) follow, the large ones shared out between the
  // threads. In the forward sweep a group's updates to rows of the top part go to that group's
  // own copy of those rows (`prow` holds each row's place: its own index, or n (1 + group) +
  // index), summed before the top part runs; in the backward sweep groups only read rows of the
  // top part, so they need no copies. The schedule does not depend on the thread count, so
  // neither do the results.
  int bins = 1;                          ///< 1: the sweeps run serially
  std::vector<std::vector<int>> groups;  ///< per group: its supernodes, ascending
  std::vector<int> top;                  ///< supernodes above the groups, ascending
  std::vector<int> prow;                 ///< like rows; forward-sweep places for grouped supernodes
  std::ptrdiff_t top_split = 1 << 16;    ///< top supernodes of this many entries are shared out

  std::ptrdiff_t nonzeros() const;   ///< entries of L (a relaxed supernode's zeros among them)
  std::size_t bytes() const;         ///< memory held
  /// What the factor stores: every value of the supernodes' nsrow x nscol blocks (the diagonal
  /// blocks' upper triangles too), and the bytes of the index arrays a sweep reads (rows, super,
  /// rowp, valp). A sweep streams both; a solve sweeps twice.
  std::size_t stored_values() const { return vals.size(); }
  std::size_t index_bytes() const;

  /// Splits the sweeps into `groups` groups when that pays: factors of at least `min_nonzeros`
  /// entries (the default: where sharing the work costs less than it saves); called by
  /// cholesky() with kGroups, and by the tests with min_nonzeros 0.
  void schedule(int groups, std::ptrdiff_t min_nonzeros = 200000);

  /// Solves A X = B in place: B is n x w (1 <= w <= 8), row-major (row i = w right-hand-side
  /// entries). Thread-safe (its scratch is per calling thread); on the library's threads when
  /// the factor has a schedule (bins > 1), with the same result on any number of them.
  void solve(double* B, int w) const;
};

/// Groups of the sweeps' schedule (cholesky()): a fixed number, so that results do not depend on
/// the thread count (the top part's large supernodes are shared out between all the threads).
/// More groups make the top part larger: on 2 cores 4 groups were slower than 2.
constexpr int kGroups = 2;

/// Factor of the SPD matrix A (full symmetric storage). Throws Error when A is not positive
/// definite. use_cholmod needs cholmod_available().
CholeskyFactor cholesky(const Eigen::SparseMatrix<double>& A, bool use_cholmod);

bool cholmod_available();

/// Unknowns from which CHOLMOD tries METIS's ordering beside AMD's and keeps the one with less
/// fill (bench/results/blender.md, "Ordering"); the memory estimate analyses the same way.
constexpr long long kMetisMinUnknowns = 10000;

/// Held while CHOLMOD orders: METIS keeps its random state in globals, so orderings computed at
/// once by two threads would depend on timing (and so would a factor's round-off).
std::mutex& ordering_mutex();

}  // namespace mbi::interp::detail
