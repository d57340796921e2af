#pragma once
// Contact of embedded points (the dense surface's vertices, or any subset) with analytic
// colliders, as a potential of the control nodes for sim::Simulator (method.md fact 16).
//
//   auto deformer = std::make_shared<pipeline::Deformer>(U, T, contact_points, options);
//   auto contact = std::make_shared<pipeline::SurfaceContact>(deformer, colliders, 1e4);
//   sim.set_potential(contact);
//   per step: sim.step();   // the simulator poses the colliders at each substep's end
//
// The dense positions are p = W x (W the deformer's linear map, method.md facts 1 and 11), so
// the energy E(x) = sum_points sum_colliders k/2 min(d(p), 0)^2 (a quadratic penalty on the
// signed distance d, fact 15) has the exact gradient W^T g, g_p = k min(d, 0) n: one
// Deformer::vjp. Its Hessian W^T K W is dense for modified-BI; the step gets the surrogate
// k (b (x) n)(b (x) n)^T per penetrating point and collider, with b the point's BI weights in
// its own element: positive semi-definite and inside the FEM's element pattern.
//
// Units: stiffness k in N/m per point; positions in m; energy in J. One SurfaceContact is not
// for several threads at once (it keeps scratch positions).
#include <mbi/pipeline/colliders.hpp>
#include <mbi/pipeline/deformer.hpp>
#include <mbi/sim/potential.hpp>

#include <memory>
#include <vector>

namespace mbi::pipeline {

class SurfaceContact : public sim::Potential {
 public:
  /// deformer: 3D, its points are the contact points. colliders: checked (Error naming
  /// "collider i" and the field). stiffness: N/m, finite and > 0.
  SurfaceContact(std::shared_ptr<const Deformer> deformer, std::vector<Collider> colliders,
                 double stiffness);

  /// Time (s) at which the colliders are posed; the simulator sets the end of each substep
  /// (begin_substep).
  void set_time(double time);
  void begin_substep(double end_time, const Eigen::Ref<const Eigen::VectorXd>& x,
                     const Eigen::Ref<const Eigen::VectorXd>& v) override;
  double time() const { return time_; }
  const std::vector<Collider>& colliders() const { return colliders_; }
  double stiffness() const { return stiffness_; }

  /// The contact points' positions (p x 3) at node positions x (3 n stacked, as the simulator's).
  Eigen::MatrixXd points(const Eigen::Ref<const Eigen::VectorXd>& x) const;

  double energy(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                    Eigen::Ref<Eigen::VectorXd> gradient) const override;
  void hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>& x,
                      std::vector<sim::NodeBlock>& blocks) const override;

 private:
  void deform(const Eigen::Ref<const Eigen::VectorXd>& x) const;  // into positions_

  std::shared_ptr<const Deformer> deformer_;
  std::vector<Collider> colliders_;
  double stiffness_ = 0.0;
  double time_ = 0.0;
  mutable Eigen::MatrixXd X_, positions_, dE_dp_;
};

}  // namespace mbi::pipeline
