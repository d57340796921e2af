// Preconditioned conjugate gradients for the modified-BI m-block, several right-hand sides at once.
#include "linalg/iterative.hpp"

#include "runtime/threads.hpp"

#include <mbi/error.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace mbi::interp::detail {

namespace {

// Q = A P, rows in parallel (A row-major, P and Q n x w column-major, w <= 3): one pass over A
// serves all the columns.
void product(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A, const Eigen::MatrixXd& P, Eigen::MatrixXd& Q) {
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* val = A.valuePtr();
  const Eigen::Index n = A.rows(), w = P.cols();
  if (w > 3) throw Error("the iterative solve takes at most 3 right-hand sides at once");
  const int nt = thread_count(A.nonZeros() * w, 1 << 15);
  const double* p = P.data();
  double* q = Q.data();
  parallel_blocks(n, 1024, nt, [&](long long r0, long long r1) {
    for (long long r = r0; r < r1; ++r) {
      double s[3] = {0, 0, 0};
      for (int k = outer[r]; k < outer[r + 1]; ++k)
        for (Eigen::Index c = 0; c < w; ++c) s[c] += val[k] * p[c * n + inner[k]];
      for (Eigen::Index c = 0; c < w; ++c) q[c * n + r] = s[c];
    }
  });
}

}  // namespace

PcgSolver::PcgSolver(const Eigen::SparseMatrix<double>& A) : A_(A) {
  ic_.compute(A);
  if (ic_.info() != Eigen::Success)
    throw Error("the incomplete Cholesky preconditioner of the iterative solve could not be built");
}

int PcgSolver::solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& X, const Tolerance& tol, int max_iterations) const {
  const Eigen::Index n = A_.rows(), w = B.cols();
  Eigen::MatrixXd R(n, w), Z(n, w), P(n, w), Q(n, w);
  product(A_, X, Q);
  R = B - Q;
  // a start worse than zero (the previous frame far from this one) is dropped
  for (Eigen::Index c = 0; c < w; ++c)
    if (R.col(c).norm() > B.col(c).norm()) {
      X.col(c).setZero();
      R.col(c) = B.col(c);
    }
  std::vector<char> active(static_cast<size_t>(w), 1);  // a column that stops stays stopped
  // per column: r^T z, and the last kDelay terms alpha_j r_j^T z_j (Hestenes-Stiefel)
  Eigen::ArrayXd rz(w);
  Eigen::ArrayXXd terms = Eigen::ArrayXXd::Zero(kDelay, w);
  Z = ic_.solve(R);
  P = Z;
  for (Eigen::Index c = 0; c < w; ++c) rz(c) = R.col(c).dot(Z.col(c));
  int it = 0;
  for (;; ++it) {
    bool any = false;
    double worst = 0;
    for (Eigen::Index c = 0; c < w; ++c) {
      if (!active[c]) continue;
      if (!std::isfinite(rz(c)))
        throw Error("the iterative solve's residual is not finite (a non-finite or huge right-hand side?)");
      const double goal = tol.relative ? tol.energy * std::sqrt(std::abs(B.col(c).dot(X.col(c)))) : tol.energy;
      // before the first step, r^T M^-1 r (the squared A-norm of the error were M = A), 100 times over
      const double estimate = it == 0 ? 100 * std::sqrt(std::max(0.0, rz(c))) : std::sqrt(terms.col(c).sum());
      active[c] = estimate > goal || (it > 0 && it < kDelay);  // the estimate needs kDelay terms
      any = any || active[c];
      worst = std::max(worst, estimate / goal);
    }
    if (!any) return it;
    if (it >= max_iterations)
      throw Error("the iterative solve did not converge within " + std::to_string(max_iterations) +
                  " iterations (its error estimate is " + std::to_string(worst) + " times the tolerance)");
    product(A_, P, Q);
    for (Eigen::Index c = 0; c < w; ++c) {
      if (!active[c]) continue;
      const double a = rz(c) / P.col(c).dot(Q.col(c));
      X.col(c) += a * P.col(c);
      R.col(c) -= a * Q.col(c);
      terms(it % kDelay, c) = a * rz(c);
    }
    Z = ic_.solve(R);
    for (Eigen::Index c = 0; c < w; ++c) {
      if (!active[c]) continue;
      const double rz_new = R.col(c).dot(Z.col(c));
      P.col(c) = Z.col(c) + (rz_new / rz(c)) * P.col(c);
      rz(c) = rz_new;
    }
  }
}

std::ptrdiff_t PcgSolver::preconditioner_nonzeros() const {
  return ic_.matrixL().nonZeros();
}

std::size_t PcgSolver::bytes() const {
  const auto sparse = [](auto nnz, auto rows) {
    return static_cast<std::size_t>(nnz) * (sizeof(double) + sizeof(int)) +
           static_cast<std::size_t>(rows + 1) * sizeof(int);
  };
  return sparse(A_.nonZeros(), A_.rows()) + sparse(preconditioner_nonzeros(), A_.rows()) +
         static_cast<std::size_t>(A_.rows()) * (sizeof(double) + 2 * sizeof(int));
}

}  // namespace mbi::interp::detail
