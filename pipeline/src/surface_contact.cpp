#include <mbi/error.hpp>
#include <mbi/pipeline/contact_laws.hpp>
#include <mbi/pipeline/surface_contact.hpp>
#include <mbi/interp/adjoint.hpp>

#include <Eigen/Geometry>
#include <algorithm>
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

/// Whether the point's Bernstein weights (b_i b_j products) are >= 0, up to a deviation from its
/// element's Bezier hull of 1e-8 of the element's size (far inside gather's margin).
bool in_hull(const interp::Embedding& emb, Eigen::Index p) { return emb.bary.row(p).minCoeff() >= -1e-9; }

}  // namespace

SurfaceContact::SurfaceContact(std::shared_ptr<const Deformer> deformer, std::vector<Collider> colliders,
                               double stiffness)
    : deformer_(std::move(deformer)), colliders_(std::move(colliders)), stiffness_(stiffness) {
  if (!deformer_) throw Error("surface contact needs a deformer");
  if (deformer_->dim() != 3)
    throw Error("surface contact needs a 3D deformer, got " + std::to_string(deformer_->dim()) + "D");
  if (!std::isfinite(stiffness) || stiffness <= 0)
    throw Error("contact stiffness must be finite and > 0 N/m, got " + std::to_string(stiffness));
  for (size_t i = 0; i < colliders_.size(); ++i) {
    check_collider(colliders_[i], "collider " + std::to_string(i));
    lipschitz_.push_back(distance_lipschitz(colliders_[i]));
    steepest_ = std::max(steepest_, lipschitz_.back());
  }
  const Eigen::MatrixXd& U = deformer_->rest_positions();
  diagonal_ = (U.colwise().maxCoeff() - U.colwise().minCoeff()).norm();
  max_depth_ = 1e-3 * diagonal_;
  friction_velocity_ = 1e-4 * diagonal_;
  index_points();
  set_time(0.0);
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

void SurfaceContact::index_points() {
  const interp::Embedding& emb = deformer_->embedding();
  const int m = deformer_->elements();
  element_start_.assign(static_cast<size_t>(m) + 1, 0);
  for (Eigen::Index p = 0; p < emb.bary.rows(); ++p) {
    if (in_hull(emb, p)) ++element_start_[emb.element(p) + 1];
    else unbounded_.push_back(p);
  }
  for (int e = 0; e < m; ++e) element_start_[e + 1] += element_start_[e];
  element_points_.resize(static_cast<size_t>(element_start_[m]));
  std::vector<int> next(element_start_.begin(), element_start_.end() - 1);
  for (Eigen::Index p = 0; p < emb.bary.rows(); ++p)
    if (in_hull(emb, p)) element_points_[next[emb.element(p)]++] = static_cast<int>(p);
  const size_t points = static_cast<size_t>(emb.bary.rows());
  start_distance_.resize(element_points_.size());
  element_distance_.resize(static_cast<size_t>(m));
  offset_.assign(static_cast<size_t>(m), 0.0);
  shift_.assign(static_cast<size_t>(m), 0.0);
  exact_.assign(static_cast<size_t>(m), 0);
  near_.assign(static_cast<size_t>(m), 0);
  slip_first_.assign(points, -1);
  row_of_.assign(points, -1);
  unguarded_.assign(points * colliders_.size(), 0);
}

void SurfaceContact::set_time(double time) {
  if (!std::isfinite(time)) throw Error("contact time must be finite");
  time_ = time;
  reference_ = false;  // the distances of begin_substep_at are of another pose
  posed_.clear();
  for (const Collider& c : colliders_) posed_.push_back(posed(c, time));
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
                                      const Eigen::Ref<const Eigen::VectorXd>& v) {
  if (!std::isfinite(start_time)) throw Error("contact time must be finite");
  check_size(x);
  check_size(v, "node velocities");
  // The last substep's start distances still bound this one's (carried), unless the time was set
  // or a collider replaced since.
  const bool carry = reference_;
  const double previous = time_;
  set_time(end_time);
  for (const Slip& s : slips_) slip_first_[static_cast<size_t>(s.point)] = -1;
  slips_.clear();
  for (size_t k : unguarded_set_) unguarded_[k] = 0;
  unguarded_set_.clear();
  started_ = true;
  const size_t C = colliders_.size();
  const double h = end_time - start_time;
  smoothing_ = friction_velocity_ * h;
  // The start's sample also takes the elements within twice the substep's move at the start
  // velocities: their points get their own distances, the others their element's bound.
  const int m = deformer_->elements();
  Eigen::VectorXd band = Eigen::VectorXd::Zero(m);
  if (h > 0) {
    const interp::BezierPoints BV = deformer_->bezier(nodes(v));
    const Eigen::Index K = BV.rows() / m;
    for (int e = 0; e < m; ++e) {
      const double move = 2 * h * BV.middleRows(e * K, K).rowwise().norm().maxCoeff();
      band(e) = std::isfinite(move) ? move : 0.0;
    }
  }
  Sample& S = at_;
  S.B = deformer_->bezier(nodes(x));
  if (carry) carry_reference(S.B, previous);
  gather(S.B, band, S.points);
  select(S.points, S.embedding);
  evaluate(S.B, S.embedding, S.P);
  ++counts_.substeps;
  counts_.substep_points += static_cast<long long>(S.points.size());
  std::vector<double> least(S.points.size(), kInf);
  for (size_t i = 0; i < S.points.size(); ++i)
    for (size_t c = 0; c < C; ++c) {
      const Eigen::Index p = S.points[i];
      const Eigen::Vector3d q = S.P.row(static_cast<Eigen::Index>(i)).transpose();
      const Distance d = signed_distance(posed_[c], q, end_time);
      least[i] = std::min(least[i], d.value);
      if (!(d.value > -max_depth_)) {
        unguarded_[static_cast<size_t>(p) * C + c] = 1;
        unguarded_set_.push_back(static_cast<size_t>(p) * C + c);
      }
      if (d.value >= 0 || colliders_[c].friction == 0 || !(h > 0)) continue;
      const double force = -contact::normal_energy(d.value, stiffness_, depth(p, c)).slope;
      Slip s;
      s.point = static_cast<int>(p);
      s.weight = colliders_[c].friction * force;
      s.tangent = tangent_basis(d.normal);
      s.anchor = q + collider_displacement(colliders_[c], q, start_time, end_time);
      if (!(s.weight > 0 && std::isfinite(s.weight))) continue;
      if (slip_first_[static_cast<size_t>(p)] < 0) slip_first_[static_cast<size_t>(p)] = static_cast<int>(slips_.size());
      slips_.push_back(s);
    }
  set_reference(S, least, carry);
  forget();  // guards and slips changed; the slips' points are evaluated from now on
}

void SurfaceContact::carry_reference(const interp::BezierPoints& B, double previous) {
  // A collider's distance at this pose is its distance at the last one at the material point's
  // place then: the points of an element moved relative to it by at most the largest such move
  // of its Bezier points (the move is affine in the point), and the distance by lipschitz times that.
  const int m = deformer_->elements();
  const Eigen::Index K = B.rows() / m;
  for (int e = 0; e < m; ++e) {
    double shift = 0.0;
    for (size_t k = 0; k < colliders_.size(); ++k)
      for (Eigen::Index j = 0; j < K; ++j)
        shift = std::max(shift, lipschitz_[k] * collider_displacement(colliders_[k], B.row(e * K + j).transpose(),
                                                                      time_, previous).norm());
    shift_[static_cast<size_t>(e)] = shift;
  }
  reference_ = true;
}

void SurfaceContact::set_reference(const Sample& S, const std::vector<double>& least, bool carry) {
  const int m = deformer_->elements();
  const Eigen::Index K = S.B.rows() / m;
  for (size_t i = 0; i < S.points.size(); ++i) row_of_[static_cast<size_t>(S.points[i])] = static_cast<int>(i);
  const auto distance = [&](int p) {  // NaN: always a candidate
    const double d = least[static_cast<size_t>(row_of_[static_cast<size_t>(p)])];
    return std::isnan(d) ? -kInf : d;
  };
  std::vector<std::pair<double, int>> order;
  for (int e = 0; e < m; ++e) {
    const size_t u = static_cast<size_t>(e);
    const int first = element_start_[e], last = element_start_[e + 1];
    const auto Be = S.B.middleRows(e * K, K);
    if (!near_[u]) {  // no point evaluated: the hull's bound for all
      double d = kInf;
      for (size_t k = 0; k < colliders_.size(); ++k) d = std::min(d, hull_lower(Be, k));
      element_distance_[u] = d;
      exact_[u] = 0;
      offset_[u] = 0.0;
      continue;
    }
    order.clear();
    if (carry && exact_[u]) {
      // the evaluated prefix gets its distances, the rest keeps its bounds less the move since
      const double moved = (Be - reference_B_.middleRows(e * K, K)).rowwise().norm().maxCoeff();
      offset_[u] += steepest_ * moved + shift_[u];
      int i = first;
      for (; i < last && row_of_[static_cast<size_t>(element_points_[i])] >= 0; ++i)
        order.emplace_back(distance(element_points_[i]) + offset_[u], element_points_[i]);
      std::sort(order.begin(), order.end());
      const size_t evaluated = order.size();
      for (; i < last; ++i) order.emplace_back(start_distance_[static_cast<size_t>(i)], element_points_[i]);
      std::inplace_merge(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(evaluated), order.end());
    } else {  // every point evaluated
      for (int i = first; i < last; ++i) order.emplace_back(distance(element_points_[i]), element_points_[i]);
      std::sort(order.begin(), order.end());
      offset_[u] = 0.0;
      exact_[u] = 1;
    }
    for (int i = first; i < last; ++i) {
      start_distance_[static_cast<size_t>(i)] = order[static_cast<size_t>(i - first)].first;
      element_points_[static_cast<size_t>(i)] = order[static_cast<size_t>(i - first)].second;
    }
  }
  for (Eigen::Index p : S.points) row_of_[static_cast<size_t>(p)] = -1;
  std::fill(shift_.begin(), shift_.end(), 0.0);  // the colliders stay posed within the substep
  reference_B_ = S.B;
  reference_ = true;
}

double SurfaceContact::depth(Eigen::Index point, size_t collider) const {
  if (!started_ || unguarded_[static_cast<size_t>(point) * colliders_.size() + collider]) return kInf;
  return max_depth_;
}

void SurfaceContact::check_size(const Eigen::Ref<const Eigen::VectorXd>& x, const char* what) const {
  const int n = deformer_->vertices();
  if (x.size() != 3 * n)
    throw Error(std::string("contact: ") + what + " must have " + std::to_string(3 * n) + " entries, got " +
                std::to_string(x.size()));
}

const Eigen::MatrixXd& SurfaceContact::nodes(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  check_size(x);
  const int n = deformer_->vertices();
  X_.resize(n, 3);
  for (int i = 0; i < n; ++i) X_.row(i) = x.segment<3>(3 * i).transpose();
  return X_;
}

double SurfaceContact::hull_lower(const Eigen::Ref<const interp::BezierPoints>& Be, size_t k) const {
  const Collider& col = posed_[k];
  if (col.shape == ColliderShape::Plane) {  // linear: least at a Bezier point
    double lower = kInf;
    for (Eigen::Index j = 0; j < Be.rows(); ++j) lower = std::min(lower, signed_distance(col, Be.row(j).transpose(), time_).value);
    return lower;
  }
  const Eigen::RowVector3d c = Be.colwise().mean();
  const double r = (Be.rowwise() - c).rowwise().norm().maxCoeff();
  return signed_distance(col, c.transpose(), time_).value - lipschitz_[k] * r;
}

void SurfaceContact::gather(const interp::BezierPoints& B, const Eigen::VectorXd& reach,
                            std::vector<Eigen::Index>& points) const {
  const int m = deformer_->elements();
  const Eigen::Index K = B.rows() / m;
  points.clear();
  std::fill(near_.begin(), near_.end(), 0);
  for (int e = 0; e < m; ++e) {
    const int first = element_start_[e], last = element_start_[e + 1];
    if (first == last) continue;
    const auto Be = B.middleRows(e * K, K);
    const Eigen::RowVector3d c = Be.colwise().mean();
    const double r = (Be.rowwise() - c).rowwise().norm().maxCoeff();
    // far beyond round-off of the points' positions and of the per-point tests
    const double margin = 4e-6 * (diagonal_ + c.norm() + r + reach(e));
    bool near = false;
    for (size_t k = 0; k < colliders_.size() && !near; ++k) near = hull_lower(Be, k) < lipschitz_[k] * reach(e) + margin;
    if (!near) continue;
    double within = kInf;
    if (reference_) {
      // A point moved by at most its element's largest Bezier move since the substep's start:
      // its distance fell by at most steepest_ times that.
      const double moved = (Be - reference_B_.middleRows(e * K, K)).rowwise().norm().maxCoeff();
      within = steepest_ * (moved + reach(e)) + shift_[static_cast<size_t>(e)] + margin;
      if (!exact_[static_cast<size_t>(e)] && !(element_distance_[static_cast<size_t>(e)] < within)) continue;
      within += offset_[static_cast<size_t>(e)];  // the element's stored bounds are its points' plus that
    }
    near_[static_cast<size_t>(e)] = 1;  // its points are taken by the rules below
    const bool ordered = reference_ && exact_[static_cast<size_t>(e)];  // by start distance: a prefix
    for (int i = first; i < last && !(ordered && !(start_distance_[static_cast<size_t>(i)] < within)); ++i)
      points.push_back(element_points_[static_cast<size_t>(i)]);
  }
  for (Eigen::Index p : unbounded_) points.push_back(p);
  const interp::Embedding& emb = deformer_->embedding();
  for (size_t i = 0; i < slips_.size(); ++i) {  // friction energy is never 0
    const Eigen::Index p = slips_[i].point;
    if (slip_first_[static_cast<size_t>(p)] == static_cast<int>(i) && in_hull(emb, p) && !near_[static_cast<size_t>(emb.element(p))])
      points.push_back(p);
  }
}

void SurfaceContact::select(const std::vector<Eigen::Index>& points, interp::Embedding& subset) const {
  const interp::Embedding& emb = deformer_->embedding();
  const Eigen::Index k = static_cast<Eigen::Index>(points.size());
  subset.element.resize(k);
  subset.bary.resize(k, emb.bary.cols());
  for (Eigen::Index i = 0; i < k; ++i) {
    subset.element(i) = emb.element(points[static_cast<size_t>(i)]);
    subset.bary.row(i) = emb.bary.row(points[static_cast<size_t>(i)]);
  }
}

void SurfaceContact::evaluate(const interp::BezierPoints& B, const interp::Embedding& subset,
                              Eigen::MatrixXd& out) const {
  out.resize(subset.size(), 3);
  if (subset.size() == 0) return;
  interp::evaluate<double>(B, subset, interp::PointsRef<double>(out), deformer_->options().threads);
}

const SurfaceContact::Sample& SurfaceContact::sample(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  check_size(x);
  if (at_.valid && at_.x == x) return at_;
  terms_valid_ = at_.valid = false;
  at_.B = deformer_->bezier(nodes(x));
  gather(at_.B, Eigen::VectorXd::Zero(deformer_->elements()), at_.points);
  select(at_.points, at_.embedding);
  evaluate(at_.B, at_.embedding, at_.P);
  ++counts_.evaluations;
  counts_.candidates += static_cast<long long>(at_.points.size());
  at_.x = x;
  at_.valid = true;
  return at_;
}

const SurfaceContact::Sample& SurfaceContact::sample(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                     const Eigen::Ref<const Eigen::VectorXd>& dx) const {
  check_size(x);
  check_size(dx);
  if (along_.valid && along_.x == x && along_.dx == dx) return along_;
  along_.valid = false;
  along_.B = at_.valid && at_.x == x ? at_.B : deformer_->bezier(nodes(x));
  const interp::BezierPoints BD = deformer_->bezier(nodes(dx));
  // A point moves by at most its element's largest Bezier move; the cap needs 0.9 of its room
  // above -max_depth to reach past it before it acts (contact::advance), the line the move itself.
  const int m = deformer_->elements();
  const Eigen::Index K = BD.rows() / m;
  Eigen::VectorXd reach(m);
  for (int e = 0; e < m; ++e) reach(e) = BD.middleRows(e * K, K).rowwise().norm().maxCoeff() / 0.9;
  gather(along_.B, reach, along_.points);
  select(along_.points, along_.embedding);
  evaluate(BD, along_.embedding, along_.D);
  positions_at(x, along_.B, along_.points, along_.P);
  ++counts_.moves;
  counts_.move_candidates += static_cast<long long>(along_.points.size());
  along_.x = x;
  along_.dx = dx;
  along_.valid = true;
  return along_;
}

void SurfaceContact::positions_at(const Eigen::Ref<const Eigen::VectorXd>& x, const interp::BezierPoints& B,
                                  const std::vector<Eigen::Index>& points, Eigen::MatrixXd& P) const {
  // the rows at_ has at x (the same values: a point's evaluation is its own) are copied
  const bool kept = at_.valid && at_.x == x;
  if (kept)
    for (size_t j = 0; j < at_.points.size(); ++j) row_of_[static_cast<size_t>(at_.points[j])] = static_cast<int>(j);
  std::vector<Eigen::Index> missing, rows;
  P.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) {
    const int j = kept ? row_of_[static_cast<size_t>(points[i])] : -1;
    if (j >= 0) {
      P.row(static_cast<Eigen::Index>(i)) = at_.P.row(j);
    } else {
      missing.push_back(points[i]);
      rows.push_back(static_cast<Eigen::Index>(i));
    }
  }
  if (kept)
    for (Eigen::Index p : at_.points) row_of_[static_cast<size_t>(p)] = -1;
  select(missing, subset_);
  Eigen::MatrixXd Q;
  evaluate(B, subset_, Q);
  for (size_t k = 0; k < rows.size(); ++k) P.row(rows[k]) = Q.row(static_cast<Eigen::Index>(k));
}

Eigen::MatrixXd SurfaceContact::points(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  return deformer_->deform(nodes(x));
}

int SurfaceContact::touching(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const Sample& S = sample(x);
  int count = 0;
  for (Eigen::Index i = 0; i < S.P.rows(); ++i)
    for (const Collider& c : posed_)
      if (signed_distance(c, S.P.row(i).transpose(), time_).value < 0) {
        ++count;
        break;
      }
  return count;
}

SurfaceContact::Term SurfaceContact::term(Eigen::Index p, const Eigen::Vector3d& q) const {
  Term t;
  for (size_t c = 0; c < colliders_.size(); ++c) {
    const Distance d = signed_distance(posed_[c], q, time_);
    if (d.value >= 0) continue;
    const contact::Law law = contact::normal_energy(d.value, stiffness_, depth(p, c));
    t.energy += law.value;
    t.gradient += law.slope * d.normal;
    t.hessian.noalias() += law.curvature * d.normal * d.normal.transpose();
    t.active = true;
  }
  for (size_t slip = static_cast<size_t>(std::max(slip_first_[static_cast<size_t>(p)], 0));
       slip_first_[static_cast<size_t>(p)] >= 0 && slip < slips_.size() && slips_[slip].point == p; ++slip) {
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
  const Sample& S = sample(x);  // forgets the terms when x changes
  if (terms_valid_) return terms_;
  terms_.clear();
  for (size_t i = 0; i < S.points.size(); ++i) {
    const Term t = term(S.points[i], S.P.row(static_cast<Eigen::Index>(i)).transpose());
    if (t.active) terms_.push_back({S.points[i], t});
  }
  terms_valid_ = true;
  active_valid_ = false;
  counts_.active += static_cast<long long>(terms_.size());
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
  Eigen::MatrixXd G(static_cast<Eigen::Index>(active.size()), 3);
  for (size_t i = 0; i < active.size(); ++i) G.row(static_cast<Eigen::Index>(i)) = active[i].term.gradient.transpose();
  // W^T restricted to the active points (the others have zero rows): exact, fact 11
  add_transpose(active_embedding(x), G, gradient);
}

const interp::Embedding& SurfaceContact::active_embedding(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const std::vector<Active>& active = terms(x);  // forgets the rows when the terms change
  if (active_valid_) return active_;
  std::vector<Eigen::Index> points(active.size());
  for (size_t i = 0; i < active.size(); ++i) points[i] = active[i].point;
  select(points, active_);
  active_valid_ = true;
  return active_;
}

void SurfaceContact::add_transpose(const interp::Embedding& subset, const Eigen::MatrixXd& G,
                                   Eigen::Ref<Eigen::VectorXd> out) const {
  const Eigen::MatrixXd& U = deformer_->rest_positions();
  const int m = deformer_->elements();
  interp::BezierPoints GB(static_cast<Eigen::Index>(m) * 10, 3);
  interp::evaluate_transpose(subset, G, m, GB, deformer_->options().threads);
  Eigen::MatrixXd GX(U.rows(), 3), GMX(U.rows(), 3);
  interp::VertexMatrices GM(3 * U.rows(), 3);
  interp::bezier_transpose(U, deformer_->elements_matrix(), GB, GX, GM);
  if (deformer_->method() == Method::ModifiedBI) deformer_->solver().solve_transpose(GM, GMX);
  if (deformer_->method() == Method::Phong) deformer_->phong().M_transpose(GM, GMX);
  if (deformer_->method() != Method::BI) GX += GMX;
  for (Eigen::Index i = 0; i < GX.rows(); ++i) out.segment<3>(3 * i) += GX.row(i).transpose();
}

bool SurfaceContact::add_hessian_product(const Eigen::Ref<const Eigen::VectorXd>& x,
                                         const Eigen::Ref<const Eigen::VectorXd>& v,
                                         Eigen::Ref<Eigen::VectorXd> out) const {
  if (deformer_->method() == Method::BI) return false;  // the blocks are W^T K W already
  check_size(v);
  const std::vector<Active>& active = terms(x);
  if (active.empty()) return true;
  const interp::Embedding& rows = active_embedding(x);
  Eigen::MatrixXd G;  // W v at the active points (p is linear in x), then K_p times it
  evaluate(deformer_->bezier(nodes(v)), rows, G);
  for (size_t i = 0; i < active.size(); ++i) {
    const Eigen::Index r = static_cast<Eigen::Index>(i);
    G.row(r) = (active[i].term.hessian * G.row(r).transpose()).transpose();
  }
  add_transpose(rows, G, out);
  return true;
}

void SurfaceContact::hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>& x,
                                    std::vector<sim::NodeBlock>& blocks) const {
  const interp::Embedding& emb = deformer_->embedding();
  const Eigen::MatrixXi& T = deformer_->elements_matrix();
  // summed per element first: one block per node pair of a touched element, not per point
  element_block_.resize(static_cast<size_t>(deformer_->elements()), -1);
  for (const Active& a : terms(x)) {
    const int e = emb.element(a.point);
    if (element_block_[e] < 0) {
      element_block_[e] = static_cast<int>(blocks.size());
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j <= i; ++j) blocks.push_back({T(e, i), T(e, j), Eigen::Matrix3d::Zero()});
    }
    sim::NodeBlock* b = &blocks[static_cast<size_t>(element_block_[e])];
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j <= i; ++j) (b++)->value.noalias() += (emb.bary(a.point, i) * emb.bary(a.point, j)) * a.term.hessian;
  }
  for (const Active& a : terms(x)) element_block_[emb.element(a.point)] = -1;
}

double SurfaceContact::max_step(const Eigen::Ref<const Eigen::VectorXd>& x,
                                const Eigen::Ref<const Eigen::VectorXd>& dx) const {
  if (!started_ || std::isinf(max_depth_)) return 1.0;
  const Sample& S = sample(x, dx);  // p is linear in x: the points move by W dx
  double s = 1.0;
  for (size_t i = 0; i < S.points.size(); ++i)
    for (size_t c = 0; c < colliders_.size(); ++c) {
      if (std::isinf(depth(S.points[i], c))) continue;
      const Eigen::Index r = static_cast<Eigen::Index>(i);
      s = std::min(s, contact::advance(posed_[c], S.P.row(r).transpose(), S.D.row(r).transpose(), time_, max_depth_));
    }
  return s;
}

void SurfaceContact::begin_line(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& dx) {
  const Sample& S = sample(x, dx);
  line_start_ = x;
  line_move_ = dx;
  line_points_.clear();
  for (size_t i = 0; i < S.points.size(); ++i) {
    const Eigen::Index p = S.points[i], r = static_cast<Eigen::Index>(i);
    bool near = slip_first_[static_cast<size_t>(p)] >= 0;  // friction energy is never 0
    // d(p + s D) >= d(p) - L |D| for s in [0, 1]; the margin covers W (x + s dx) != p + s W dx
    const double reach = S.D.row(r).norm() + 1e-6 * (diagonal_ + S.P.row(r).norm() + S.D.row(r).norm());
    for (size_t c = 0; c < colliders_.size() && !near; ++c)
      near = signed_distance(posed_[c], S.P.row(r).transpose(), time_).value < lipschitz_[c] * reach;
    if (near) line_points_.push_back(r);
  }
  line_valid_ = true;
}

double SurfaceContact::energy_along(double s) const {
  if (!line_valid_) throw Error("contact: energy_along needs begin_line (after the last substep or setting)");
  if (!(s >= 0 && s <= 1)) return energy(line_start_ + s * line_move_);
  const Sample& S = sample(line_start_, line_move_);  // kept from begin_line unless moved elsewhere
  double E = 0.0;
  for (Eigen::Index r : line_points_) E += term(S.points[static_cast<size_t>(r)], (S.P.row(r) + s * S.D.row(r)).transpose()).energy;
  return E;
}

}  // namespace mbi::pipeline
