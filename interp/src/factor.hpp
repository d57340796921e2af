#pragma once
// Sparse Cholesky factor of the modified-BI m-block (internal): P A P^T = L L^T, computed by
// Eigen's SimplicialLLT (always there) or CHOLMOD's supernodal factorization (when the build has
// it), and stored one way: by supernodes (a simplicial factor is one column a supernode). The
// per-frame solve then runs our own triangular sweeps over all right-hand sides at once (the d
// components of M share the matrix), reading the factor once per sweep instead of once per
// component as Eigen's solve does.
#include <Eigen/SparseCore>

#include <cstddef>
#include <vector>

namespace mbi::interp::detail {

struct CholeskyFactor {
  int n = 0;
  std::vector<int> perm;             ///< (P b)[k] = b[perm[k]]
  std::vector<int> super;            ///< nsuper + 1: first column of each supernode
  std::vector<std::ptrdiff_t> rowp;  ///< nsuper + 1: supernode s's rows are rows[rowp[s] .. rowp[s+1])
  std::vector<std::ptrdiff_t> valp;  ///< nsuper + 1: its nsrow x nscol column-major block in vals
  std::vector<int> rows;             ///< first the supernode's own columns, then the rows below
  std::vector<double> vals;
  const char* method = "";           ///< "Eigen SimplicialLLT (AMD)" or "CHOLMOD supernodal (...)"

  std::ptrdiff_t nonzeros() const;   ///< entries of L
  std::size_t bytes() const;         ///< memory held

  /// Solves A X = B in place: B is n x w (1 <= w <= 8), row-major (row i = w right-hand-side
  /// entries). work: n w doubles.
  void solve(double* B, int w, double* work) const;
};

/// Factor of the SPD matrix A (full symmetric storage). Throws Error when A is not positive
/// definite (`who` prefixes the message). use_cholmod needs cholmod_available().
CholeskyFactor cholesky(const Eigen::SparseMatrix<double>& A, bool use_cholmod, const char* who);

bool cholmod_available();

}  // namespace mbi::interp::detail
