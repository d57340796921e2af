#pragma once
// Interactive control of the control mesh (paper Eq. 10 and Eq. 11, method.md fact 10):
// a few control vertices (handles) are dragged; the free positions and all M_i minimise E_total.
#include <mbi/interp/modified_bi.hpp>

#include <vector>

namespace mbi::interp {

enum class HandleMode {
  Hard,  ///< Eq. 10: handles are hard constraints
  Soft   ///< Eq. 11: gamma * E_pos with gamma automatic (Frobenius rule over positions)
};

struct ControlOptions {
  Options interp;                     ///< alpha, beta, pin_boundary of the underlying energy
  HandleMode mode = HandleMode::Hard;
  double gamma = 0.0;                 ///< Soft only; 0 = automatic
  /// Weight of the weak pull toward the previous pose, lambda sum_i |x_i - previous_i|^2 over the
  /// position unknowns, with lambda = regularization * ||H_xx||_F / sqrt(#position unknowns)
  /// (H_xx: position block of E_total's Hessian). It keeps the problem well-posed with fewer
  /// than d+1 affinely independent handles (any affine motion fixing the handles would
  /// otherwise be free) and is applied ONLY then, so d+1 or more spanning handles give the exact
  /// minimiser. Its bias on the result is proportional to it (about 1e-3 relative at 1e-6).
  double regularization = 1e-6;
};

/// Factorised once per handle set; solve() per drag. Unknowns per output component: m (gauge
/// pinned as in ModifiedBI, boundary dropped with pin_boundary) and the free positions (all
/// positions in Soft mode). Throws Error on an empty or repeated handle set, an index out of
/// range, alpha/beta/gamma/regularization < 0, or fewer than d+1 spanning handles with
/// regularization 0.
class HandleSolver {
 public:
  HandleSolver(const Eigen::Ref<const Eigen::MatrixXd>& U,
               const Eigen::Ref<const Eigen::MatrixXi>& T, std::vector<int> handles,
               const ControlOptions& options = {});
  ~HandleSolver();
  HandleSolver(HandleSolver&&) noexcept;
  HandleSolver& operator=(HandleSolver&&) noexcept;

  /// targets: handles.size() x d. previous: n x d pose the regulariser pulls toward (defaults
  /// to the rest pose when empty). Returns all control positions X (n x d); M via last_M().
  Eigen::MatrixXd solve(const Eigen::Ref<const Eigen::MatrixXd>& targets,
                        const Eigen::MatrixXd& previous = Eigen::MatrixXd());
  const VertexMatrices& last_M() const;
  double gamma() const;  ///< Soft: the gamma used (automatic or given); Hard: 0
  const std::vector<int>& handles() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mbi::interp
