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
  forget();
}

void SurfaceContact::set_max_depth(double depth) {
  if (!(depth > 0)) throw Error("contact max_depth must be > 0 m (or infinity), got " + num(depth));
  max_depth_ = depth;
  forget();
}

void SurfaceContact::set_friction_velocity(double velocity) {
  if (!std::isfinite(velocity) || velocity <= 0)
    throw Error("contact friction velocity must be finite and > 0 m/s, got " + num(velocity));
  friction_velocity_ = velocity;
  forget();
}

void SurfaceContact::begin_substep(double end_time, const Eigen::Ref<const Eigen::VectorXd>& x,
                                   const Eigen::Ref<const Eigen::VectorXd>& v) {
  begin_substep_at(time_, end_time, x, v);
}

void SurfaceContact::begin_substep_at(double start_time, double end_time, const Eigen::Ref<const Eigen::VectorXd>& x,
                                      const Eigen::Ref<const Eigen::VectorXd>&) {
  if (!std::isfinite(start_time)) throw Error("contact time must be finite");
  set_time(end_time);
  at_.valid = along_.valid = false;  // a fresh deformation every substep
  const Eigen::MatrixXd& P = deform(x, at_);
  const size_t C = colliders_.size();
  guarded_.assign(static_cast<size_t>(P.rows()) * C, 0);
  slips_.clear();
  const double h = end_time - start_time;
  smoothing_ = friction_velocity_ * h;
  for (Eigen::Index p = 0; p < P.rows(); ++p)
    for (size_t c = 0; c < C; ++c) {
      const Eigen::Vector3d q = P.row(p).transpose();
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
  forget();  // guards and slips changed
}

double SurfaceContact::depth(Eigen::Index point, size_t collider) const {
  if (guarded_.empty() || !guarded_[static_cast<size_t>(point) * colliders_.size() + collider]) return kInf;
  return max_depth_;
}

const Eigen::MatrixXd& SurfaceContact::deform(const Eigen::Ref<const Eigen::VectorXd>& x, Deformed& cache) const {
  const int n = deformer_->vertices();
  if (x.size() != 3 * n)
    throw Error("contact: node positions must have " + std::to_string(3 * n) + " entries, got " +
                std::to_string(x.size()));
  if (cache.valid && cache.x == x) return cache.points;
  if (&cache == &at_) terms_valid_ = false;
  cache.valid = false;
  X_.resize(n, 3);
  for (int i = 0; i < n; ++i) X_.row(i) = x.segment<3>(3 * i).transpose();
  cache.points.resize(deformer_->points(), 3);
  deformer_->deform(X_, cache.points);
  cache.x = x;
  cache.valid = true;
  return cache.points;
}

Eigen::MatrixXd SurfaceContact::points(const Eigen::Ref<const Eigen::VectorXd>& x) const { return deform(x, at_); }

SurfaceContact::Term SurfaceContact::term(Eigen::Index p, const Eigen::Vector3d& q, size_t& slip) const {
  Term t;
  for (size_t c = 0; c < colliders_.size(); ++c) {
    const Distance d = signed_distance(colliders_[c], q, time_);
    if (d.value >= 0) continue;
    const contact::Law law = contact::normal_energy(d.value, stiffness_, depth(p, c));
    t.energy += law.value;
    t.gradient += law.slope * d.normal;
    t.hessian.noalias() += law.curvature * d.normal * d.normal.transpose();
    t.active = true;
  }
  while (slip < slips_.size() && slips_[slip].point < p) ++slip;
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

const std::vector<SurfaceContact::Active>& SurfaceContact::terms(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const Eigen::MatrixXd& P = deform(x, at_);  // forgets the terms when x changes
  if (terms_valid_) return terms_;
  terms_.clear();
  size_t slip = 0;
  for (Eigen::Index p = 0; p < P.rows(); ++p) {
    const Term t = term(p, P.row(p).transpose(), slip);
    if (t.active) terms_.push_back({p, t});
  }
  terms_valid_ = true;
  return terms_;
}

double SurfaceContact::energy(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  double E = 0.0;
  for (const Active& a : terms(x)) E += a.term.energy;
  return E;
}

void SurfaceContact::add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                                  Eigen::Ref<Eigen::VectorXd> gradient) const {
  const std::vector<Active>& active = terms(x);
  if (active.empty()) return;
  dE_dp_.setZero(deformer_->points(), 3);
  for (const Active& a : active) dE_dp_.row(a.point) = a.term.gradient.transpose();
  const Eigen::MatrixXd dE_dX = deformer_->vjp(dE_dp_);  // W^T, exact (fact 11)
  for (Eigen::Index i = 0; i < dE_dX.rows(); ++i) gradient.segment<3>(3 * i) += dE_dX.row(i).transpose();
}

void SurfaceContact::hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>& x,
                                    std::vector<sim::NodeBlock>& blocks) const {
  const interp::Embedding& emb = deformer_->embedding();
  const Eigen::MatrixXi& T = deformer_->elements_matrix();
  for (const Active& a : terms(x)) {
    const int e = emb.element(a.point);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j <= i; ++j)
        blocks.push_back({T(e, i), T(e, j), emb.bary(a.point, i) * emb.bary(a.point, j) * a.term.hessian});
  }
}

double SurfaceContact::max_step(const Eigen::Ref<const Eigen::VectorXd>& x,
                                const Eigen::Ref<const Eigen::VectorXd>& dx) const {
  if (guarded_.empty() || std::isinf(max_depth_)) return 1.0;
  const Eigen::MatrixXd& D = deform(dx, along_);  // p is linear in x: the points move by W dx
  const Eigen::MatrixXd& P = deform(x, at_);
  double s = 1.0;
  for (Eigen::Index p = 0; p < P.rows(); ++p)
    for (size_t c = 0; c < colliders_.size(); ++c) {
      if (std::isinf(depth(p, c))) continue;
      s = std::min(s, contact::advance(colliders_[c], P.row(p).transpose(), D.row(p).transpose(), time_, max_depth_));
    }
  return s;
}

void SurfaceContact::begin_line(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& dx) {
  const Eigen::MatrixXd& D = deform(dx, along_);
  const Eigen::MatrixXd& P = deform(x, at_);
  line_start_ = x;
  line_move_ = dx;
  line_points_.clear();
  size_t slip = 0;
  for (Eigen::Index p = 0; p < P.rows(); ++p) {
    while (slip < slips_.size() && slips_[slip].point < p) ++slip;
    bool near = slip < slips_.size() && slips_[slip].point == p;  // friction energy is never 0
    // d(p + s D) >= d(p) - |D| for s in [0, 1]; the margin covers W (x + s dx) != p + s W dx
    const double reach = D.row(p).norm() + 1e-6 * (diagonal_ + P.row(p).norm() + D.row(p).norm());
    for (size_t c = 0; c < colliders_.size() && !near; ++c)
      near = signed_distance(colliders_[c], P.row(p).transpose(), time_).value < reach;
    if (near) line_points_.push_back(p);
  }
  line_valid_ = true;
}

double SurfaceContact::energy_along(double s) const {
  if (!line_valid_) throw Error("contact: energy_along needs begin_line (after the last substep or setting)");
  const Eigen::MatrixXd& P = deform(line_start_, at_);  // both kept from begin_line unless evaluated elsewhere
  const Eigen::MatrixXd& D = deform(line_move_, along_);
  double E = 0.0;
  size_t slip = 0;
  const auto add = [&](Eigen::Index p) { E += term(p, (P.row(p) + s * D.row(p)).transpose(), slip).energy; };
  if (s >= 0 && s <= 1) {
    for (Eigen::Index p : line_points_) add(p);
  } else {
    for (Eigen::Index p = 0; p < P.rows(); ++p) add(p);
  }
  return E;
}

}  // namespace mbi::pipeline
