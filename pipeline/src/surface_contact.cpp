#include <mbi/error.hpp>
#include <mbi/pipeline/surface_contact.hpp>

#include <cmath>
#include <string>

namespace mbi::pipeline {

SurfaceContact::SurfaceContact(std::shared_ptr<const Deformer> deformer, std::vector<Collider> colliders,
                               double stiffness)
    : deformer_(std::move(deformer)), colliders_(std::move(colliders)), stiffness_(stiffness) {
  if (!deformer_) throw Error("surface contact needs a deformer");
  if (deformer_->dim() != 3)
    throw Error("surface contact needs a 3D deformer, got " + std::to_string(deformer_->dim()) + "D");
  if (!std::isfinite(stiffness) || stiffness <= 0)
    throw Error("contact stiffness must be finite and > 0 N/m, got " + std::to_string(stiffness));
  for (size_t i = 0; i < colliders_.size(); ++i) check_collider(colliders_[i], "collider " + std::to_string(i));
}

void SurfaceContact::set_time(double time) {
  if (!std::isfinite(time)) throw Error("contact time must be finite");
  time_ = time;
}

void SurfaceContact::begin_substep(double end_time, const Eigen::Ref<const Eigen::VectorXd>&,
                                   const Eigen::Ref<const Eigen::VectorXd>&) {
  set_time(end_time);
}

void SurfaceContact::deform(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const int n = deformer_->vertices();
  if (x.size() != 3 * n)
    throw Error("contact: node positions must have " + std::to_string(3 * n) + " entries, got " +
                std::to_string(x.size()));
  X_.resize(n, 3);
  for (int i = 0; i < n; ++i) X_.row(i) = x.segment<3>(3 * i).transpose();
  positions_.resize(deformer_->points(), 3);
  deformer_->deform(X_, positions_);
}

Eigen::MatrixXd SurfaceContact::points(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  deform(x);
  return positions_;
}

double SurfaceContact::energy(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  deform(x);
  double E = 0.0;
  for (Eigen::Index p = 0; p < positions_.rows(); ++p)
    for (const Collider& c : colliders_) {
      const double d = signed_distance(c, positions_.row(p).transpose(), time_).value;
      if (d < 0) E += 0.5 * stiffness_ * d * d;
    }
  return E;
}

void SurfaceContact::add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                                  Eigen::Ref<Eigen::VectorXd> gradient) const {
  deform(x);
  dE_dp_.setZero(positions_.rows(), 3);
  bool any = false;
  for (Eigen::Index p = 0; p < positions_.rows(); ++p)
    for (const Collider& c : colliders_) {
      const Distance d = signed_distance(c, positions_.row(p).transpose(), time_);
      if (d.value >= 0) continue;
      dE_dp_.row(p) += stiffness_ * d.value * d.normal.transpose();
      any = true;
    }
  if (!any) return;
  const Eigen::MatrixXd dE_dX = deformer_->vjp(dE_dp_);  // W^T, exact (fact 11)
  for (Eigen::Index i = 0; i < dE_dX.rows(); ++i) gradient.segment<3>(3 * i) += dE_dX.row(i).transpose();
}

void SurfaceContact::hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>& x,
                                    std::vector<sim::NodeBlock>& blocks) const {
  deform(x);
  const interp::Embedding& emb = deformer_->embedding();
  const Eigen::MatrixXi& T = deformer_->elements_matrix();
  for (Eigen::Index p = 0; p < positions_.rows(); ++p)
    for (const Collider& c : colliders_) {
      const Distance d = signed_distance(c, positions_.row(p).transpose(), time_);
      if (d.value >= 0) continue;
      const Eigen::Matrix3d nn = stiffness_ * d.normal * d.normal.transpose();
      const int e = emb.element(p);
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b <= a; ++b)
          blocks.push_back({T(e, a), T(e, b), emb.bary(p, a) * emb.bary(p, b) * nn});
    }
}

}  // namespace mbi::pipeline
