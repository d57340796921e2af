#pragma once
// Preconditioned conjugate gradients on the modified-BI m-block (internal), for control meshes
// whose direct factor would not fit: the matrix and an incomplete-Cholesky preconditioner are
// built once; each solve runs one CG per right-hand side, all columns sharing each pass over the
// matrix, from a caller-given start (the previous frame's solution).
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>

#include <cstddef>

namespace mbi::interp::detail {

class PcgSolver {
 public:
  /// Keeps the SPD matrix A (full symmetric storage) and builds the preconditioner. Throws Error
  /// when the preconditioner cannot be built.
  explicit PcgSolver(const Eigen::SparseMatrix<double>& A);
  PcgSolver() = default;

  /// A column stops once the estimate of the A-norm of its error is <= energy (times
  /// sqrt(b^T x), the A-norm of the solution, when relative). The estimate is the square root
  /// of the sum of the last kDelay terms alpha_j r_j^T z_j (Hestenes-Stiefel): a lower estimate
  /// of the error kDelay iterations back, and CG's A-norm error only decreases; so a column that
  /// takes a step takes at least kDelay. Before the first step it is 100 sqrt(r^T M^-1 r) (M the
  /// preconditioner), so a start that is already good takes none.
  struct Tolerance {
    double energy = 0;
    bool relative = false;
  };
  static constexpr int kDelay = 8;

  /// Solves A X = B column by column into X (n x w, w <= 3), starting from X as given (a column whose
  /// start is worse than zero starts from zero). Returns the largest iteration count of the
  /// columns. Throws Error when a column has not stopped after max_iterations, or when the
  /// residual is not finite.
  int solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& X, const Tolerance& tol, int max_iterations) const;

  std::ptrdiff_t preconditioner_nonzeros() const;
  std::size_t bytes() const;
  int rows() const { return static_cast<int>(A_.rows()); }

 private:
  Eigen::SparseMatrix<double, Eigen::RowMajor> A_;
  Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>> ic_;
};

}  // namespace mbi::interp::detail
