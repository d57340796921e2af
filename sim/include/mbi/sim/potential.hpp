#pragma once
// An extra potential energy that the simulator's implicit step takes from the layer above (for
// example contact at points embedded in the control mesh), method.md fact 14.
//
//   struct Spring : sim::Potential { ... };
//   sim.set_potential(std::make_shared<Spring>(...));   // nullptr removes it
//
// Positions x are the stacked node positions (3 n, m): node i, axis c at index 3 i + c.
// Energy in J, gradient dE/dx in N (J/m), Hessian blocks in N/m.
#include <Eigen/Core>
#include <vector>

namespace mbi::sim {

/// One 3x3 block of a symmetric Hessian: value = d^2 E / (dx_row dx_col^T). A block with
/// row != col stands for itself and its transpose at (col, row): give each node pair once.
/// Blocks for the same pair add up.
struct NodeBlock {
  int row = 0;
  int col = 0;
  Eigen::Matrix3d value = Eigen::Matrix3d::Zero();
};

class Potential {
 public:
  virtual ~Potential() = default;
  /// Called once at the start of every substep, before any other call of that substep: time
  /// (s) at its end (the time at which the implicit step evaluates E) and the node positions
  /// and velocities at its start (3 n), e.g. to pose moving colliders or lag friction.
  virtual void begin_substep(double /*end_time*/, const Eigen::Ref<const Eigen::VectorXd>& /*x*/,
                             const Eigen::Ref<const Eigen::VectorXd>& /*v*/) {}
  /// The same with the substep's start time (s) too; the simulator calls this one. The default
  /// forwards to begin_substep(end_time, x, v).
  virtual void begin_substep_at(double /*start_time*/, double end_time,
                                const Eigen::Ref<const Eigen::VectorXd>& x,
                                const Eigen::Ref<const Eigen::VectorXd>& v) {
    begin_substep(end_time, x, v);
  }
  /// The largest fraction s in (0, 1] of a move of the nodes from x to x + dx (3 n, m) that
  /// the potential admits (e.g. no contact point crossing a collider on the way); the step's
  /// line search starts from it. Default 1: every move is admissible.
  virtual double max_step(const Eigen::Ref<const Eigen::VectorXd>& /*x*/,
                          const Eigen::Ref<const Eigen::VectorXd>& /*dx*/) const {
    return 1.0;
  }
  /// E(x), J. Must be finite wherever the step evaluates it (or the step fails).
  virtual double energy(const Eigen::Ref<const Eigen::VectorXd>& x) const = 0;
  /// One line search: begin_line(x, dx) once, then energy_along(s) = energy(x + s dx) (to
  /// round-off) for any s, the step's fractions s in (0, 1] mostly, so that a potential can
  /// prepare the move once (e.g. points linear in x). Override both or neither; the default
  /// keeps x and dx and evaluates energy(x + s dx).
  virtual void begin_line(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& dx) {
    line_x_ = x;
    line_dx_ = dx;
  }
  virtual double energy_along(double s) const { return energy(line_x_ + s * line_dx_); }
  /// The line search took the fraction s of that move: the step's next evaluation, if any, is at
  /// x + s dx to round-off, so a potential may keep what it prepared for the move. Default: nothing.
  virtual void end_line(double /*s*/) {}
  /// Adds dE/dx (3 n, N) to `gradient`.
  virtual void add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                            Eigen::Ref<Eigen::VectorXd> gradient) const = 0;
  /// Adds H v to `out` (3 n, N/m times v's m) and returns true, where H is the Hessian that
  /// hessian_blocks stands for when those blocks are only a surrogate of it (e.g. H couples nodes
  /// outside the pattern); then each Newton step is solved with H by conjugate gradients that
  /// the blocks precondition (method.md fact 14). Default false: the blocks are H itself.
  virtual bool add_hessian_product(const Eigen::Ref<const Eigen::VectorXd>& /*x*/,
                                   const Eigen::Ref<const Eigen::VectorXd>& /*v*/,
                                   Eigen::Ref<Eigen::VectorXd> /*out*/) const {
    return false;
  }
  /// Appends the Hessian of E at x, or a symmetric positive semi-definite surrogate of it, as
  /// node blocks. Every pair (row, col) must share an element of the control mesh (the FEM's
  /// sparsity pattern); the step fails naming the first pair that does not.
  virtual void hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>& x,
                              std::vector<NodeBlock>& blocks) const = 0;

 private:
  Eigen::VectorXd line_x_, line_dx_;  // the default line search's move
};

}  // namespace mbi::sim
