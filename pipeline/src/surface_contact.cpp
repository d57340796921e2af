#include <mbi/error.hpp>
#include <mbi/pipeline/contact_laws.hpp>
#include <mbi/pipeline/surface_contact.hpp>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace mbi::pipeline {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

/// Orthonormal basis (columns) of the plane orthogonal to the unit vector n.
Eigen::Matrix<double, 3, 2> tangent_basis(const Eigen::Vector3d& n) {
  Eigen::Matrix<double, 3, 2> T;
  T.col(0) = n.unitOrthogonal();
  T.col(1) = n.cross(T.col(0));
  return T;
}

}  // namespace

SurfaceContact::SurfaceContact(std::shared_ptr<const Deformer> deformer, std::vector<Collider> colliders,
                               double stiffness)
    : deformer_(std::move(deformer)), colliders_(std::move(colliders)), stiffness_(stiffness) {
  if (!deformer_) throw Error("surface contact needs a deformer");
  if (deformer_->dim() != 3)
    throw Error("surface contact needs a 3D deformer, got " + std::to_string(deformer_->dim()) + "D");
  if (!std::isfinite(stiffness) || stiffness <= 0)
    throw Error("contact stiffness must be finite and > 0 N/m, got " + std::to_string(stiffness));
  for (size_t i = 0; i < colliders_.size(); ++i) check_collider(colliders_[i], "collider " + std::to_string(i));
  const Eigen::MatrixXd& U = deformer_->rest_positions();
  diagonal_ = (U.colwise().maxCoeff() - U.colwise().minCoeff()).norm();
  max_depth_ = 1e-3 * diagonal_;
  friction_velocity_ = 1e-4 * diagonal_;
  const Eigen::MatrixXd P = deformer_->deform(U);
  for (size_t c = 0; c < colliders_.size(); ++c)
    for (Eigen::Index p = 0; p < P.rows(); ++p) {
      const double d = signed_distance(colliders_[c], P.row(p).transpose(), 0.0).value;
      if (d <= -max_depth_)
        throw Error("collider " + std::to_string(c) + " overlaps the model at rest: contact point " +
                    std::to_string(p) + " is " + num(-d) + " m inside (at most " + num(max_depth_) +
                    " m allowed)");
    }
}

void SurfaceContact::set_time(double time) {
  if (!std::isfinite(time)) throw Error("contact time must be finite");
  time_ = time;
}

void SurfaceContact::set_max_depth(double depth) {
  if (!(depth > 0)) throw Error("contact max_depth must be > 0 m (or infinity), got " + num(depth));
  max_depth_ = depth;
}

void SurfaceContact::set_friction_velocity(double velocity) {
  if (!std::isfinite(velocity) || velocity <= 0)
    throw Error("contact friction velocity must be finite and > 0 m/s, got " + num(velocity));
  friction_velocity_ = velocity;
}

void SurfaceContact::begin_substep(double end_time, const Eigen::Ref<const Eigen::VectorXd>& x,
                                   const Eigen::Ref<const Eigen::VectorXd>& v) {
  begin_substep_at(time_, end_time, x, v);
}

void SurfaceContact::begin_substep_at(double start_time, double end_time, const Eigen::Ref<const Eigen::VectorXd>& x,
                                      const Eigen::Ref<const Eigen::VectorXd>&) {
  if (!std::isfinite(start_time)) throw Error("contact time must be finite");
  set_time(end_time);
  deform(x);
  const size_t C = colliders_.size();
  guarded_.assign(static_cast<size_t>(positions_.rows()) * C, 0);
  slips_.clear();
  const double h = end_time - start_time;
  smoothing_ = friction_velocity_ * h;
  for (Eigen::Index p = 0; p < positions_.rows(); ++p)
    for (size_t c = 0; c < C; ++c) {
      const Eigen::Vector3d q = positions_.row(p).transpose();
      const Distance d = signed_distance(colliders_[c], q, end_time);
      guarded_[static_cast<size_t>(p) * C + c] = d.value > -max_depth_;
      if (d.value >= 0 || colliders_[c].friction == 0 || !(h > 0)) continue;
      const double force = -contact::normal_energy(d.value, stiffness_, depth(p, c)).slope;
      Slip s;
      s.point = static_cast<int>(p);
      s.weight = colliders_[c].friction * force;
      s.tangent = tangent_basis(d.normal);
      s.anchor = q + collider_displacement(colliders_[c], q, start_time, end_time);
      if (s.weight > 0 && std::isfinite(s.weight)) slips_.push_back(s);
    }
}

double SurfaceContact::depth(Eigen::Index point, size_t collider) const {
  if (guarded_.empty() || !guarded_[static_cast<size_t>(point) * colliders_.size() + collider]) return kInf;
  return max_depth_;
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

SurfaceContact::Term SurfaceContact::term(Eigen::Index p, size_t& slip) const {
  Term t;
  const Eigen::Vector3d q = positions_.row(p).transpose();
  for (size_t c = 0; c < colliders_.size(); ++c) {
    const Distance d = signed_distance(colliders_[c], q, time_);
    if (d.value >= 0) continue;
    const contact::Law law = contact::normal_energy(d.value, stiffness_, depth(p, c));
    t.energy += law.value;
    t.gradient += law.slope * d.normal;
    t.hessian.noalias() += law.curvature * d.normal * d.normal.transpose();
    t.active = true;
  }
  for (; slip < slips_.size() && slips_[slip].point == p; ++slip) {
    const Slip& s = slips_[slip];
    const Eigen::Vector2d u = s.tangent.transpose() * (q - s.anchor);
    const double y = u.norm();
    t.energy += s.weight * contact::friction_f0(y, smoothing_);
    t.gradient.noalias() += (s.weight * contact::friction_f1_over_y(y, smoothing_)) * (s.tangent * u);
    t.hessian.noalias() += s.tangent * (s.weight * contact::friction_hessian(u, smoothing_)) * s.tangent.transpose();
    t.active = true;
  }
  return t;
}

double SurfaceContact::energy(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  deform(x);
  double E = 0.0;
  size_t slip = 0;
  for (Eigen::Index p = 0; p < positions_.rows(); ++p) E += term(p, slip).energy;
  return E;
}

void SurfaceContact::add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                                  Eigen::Ref<Eigen::VectorXd> gradient) const {
  deform(x);
  dE_dp_.setZero(positions_.rows(), 3);
  bool any = false;
  size_t slip = 0;
  for (Eigen::Index p = 0; p < positions_.rows(); ++p) {
    const Term t = term(p, slip);
    if (!t.active) continue;
    dE_dp_.row(p) = t.gradient.transpose();
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
  size_t slip = 0;
  for (Eigen::Index p = 0; p < positions_.rows(); ++p) {
    const Term t = term(p, slip);
    if (!t.active) continue;
    const int e = emb.element(p);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b <= a; ++b)
        blocks.push_back({T(e, a), T(e, b), emb.bary(p, a) * emb.bary(p, b) * t.hessian});
  }
}

double SurfaceContact::max_step(const Eigen::Ref<const Eigen::VectorXd>& x,
                                const Eigen::Ref<const Eigen::VectorXd>& dx) const {
  if (guarded_.empty() || std::isinf(max_depth_)) return 1.0;
  deform(dx);  // p is linear in x: the points move by W dx
  moved_ = positions_;
  deform(x);
  double s = 1.0;
  for (Eigen::Index p = 0; p < positions_.rows(); ++p)
    for (size_t c = 0; c < colliders_.size(); ++c) {
      if (std::isinf(depth(p, c))) continue;
      s = std::min(s, contact::advance(colliders_[c], positions_.row(p).transpose(), moved_.row(p).transpose(),
                                       time_, max_depth_));
    }
  return s;
}

}  // namespace mbi::pipeline
