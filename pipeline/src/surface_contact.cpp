#include <mbi/error.hpp>
#include <mbi/pipeline/contact_laws.hpp>
#include <mbi/pipeline/surface_contact.hpp>
#include <mbi/interp/parallel.hpp>

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
  take_.assign(static_cast<size_t>(m), 0);
  slip_first_.assign(points, -1);
  row_of_.assign(points, -1);
  unguarded_.assign(points * colliders_.size(), 0);
}

void SurfaceContact::set_time(double time) {
  if (!std::isfinite(time)) throw Error("contact time must be finite");
  time_ = time;
  reference_ = false;  // the distances of begin_substep_at are of another pose
  posed_.clear();
  unit_normal_.clear();
  for (const Collider& c : colliders_) {
    posed_.push_back(posed(c, time));
    unit_normal_.push_back(posed_.back().normal / posed_.back().normal.norm());  // as signed_distance divides
  }
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
  gather(S.B, band, S);
  evaluate(S.B, S.points, S.P);
  ++counts_.substeps;
  counts_.substep_points += static_cast<long long>(S.points.size());
  const long long rows = static_cast<long long>(S.points.size());
  std::vector<Distance> dist(S.points.size() * C);
  std::vector<double> least(S.points.size(), kInf);
  interp::parallel_for(rows, 1024, [&](long long b, long long e) {
    for (long long i = b; i < e; ++i)
      for (size_t c = 0; c < C; ++c) {
        const Distance d = distance(c, S.P.row(i).transpose());
        least[static_cast<size_t>(i)] = std::min(least[static_cast<size_t>(i)], d.value);
        dist[static_cast<size_t>(i) * C + c] = d;
      }
  }, deformer_->options().threads);
  for (size_t i = 0; i < S.points.size(); ++i)
    for (size_t c = 0; c < C; ++c) {
      const Eigen::Index p = S.points[i];
      const Eigen::Vector3d q = S.P.row(static_cast<Eigen::Index>(i)).transpose();
      const Distance& d = dist[i * C + c];
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
  interp::parallel_for(m, 64, [&](long long b, long long end) {
    for (long long e = b; e < end; ++e) {
      double shift = 0.0;
      for (size_t k = 0; k < colliders_.size(); ++k)
        for (Eigen::Index j = 0; j < K; ++j)
          shift = std::max(shift, lipschitz_[k] * collider_displacement(colliders_[k], B.row(e * K + j).transpose(),
                                                                        time_, previous).norm());
      shift_[static_cast<size_t>(e)] = shift;
    }
  }, deformer_->options().threads);
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
  // each element's points on one thread: the result is the same for every thread count
  interp::parallel_for(m, 32, [&](long long b, long long end) {
    std::vector<std::pair<double, int>> order;
    for (int e = static_cast<int>(b); e < static_cast<int>(end); ++e) {
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
  }, deformer_->options().threads);
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
    for (Eigen::Index j = 0; j < Be.rows(); ++j) lower = std::min(lower, distance(k, Be.row(j).transpose()).value);
    return lower;
  }
  const Eigen::RowVector3d c = Be.colwise().mean();
  const double r = (Be.rowwise() - c).rowwise().norm().maxCoeff();
  return signed_distance(col, c.transpose(), time_).value - lipschitz_[k] * r;
}

void SurfaceContact::gather(const interp::BezierPoints& B, const Eigen::VectorXd& reach, Sample& S) const {
  const int m = deformer_->elements();
  const Eigen::Index K = B.rows() / m;
  take_.resize(static_cast<size_t>(m));
  // per element on the library's threads: whether its hull comes near, and how many of its points to take
  interp::parallel_for(m, 32, [&](long long b, long long end) {
    for (int e = static_cast<int>(b); e < static_cast<int>(end); ++e) {
      const size_t u = static_cast<size_t>(e);
      near_[u] = 0;
      take_[u] = 0;
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
        within = steepest_ * (moved + reach(e)) + shift_[u] + margin;
        if (!exact_[u] && !(element_distance_[u] < within)) continue;
        within += offset_[u];  // the element's stored bounds are its points' plus that
      }
      near_[u] = 1;  // its points are taken by the rules below
      const bool ordered = reference_ && exact_[u];  // by start distance: a prefix
      int i = first;
      while (i < last && !(ordered && !(start_distance_[static_cast<size_t>(i)] < within))) ++i;
      take_[u] = i - first;
    }
  }, deformer_->options().threads);
  // each element's prefix is one run of the points; then the points outside every hull and with
  // friction, in runs of their elements as they come
  std::vector<Eigen::Index>& points = S.points;
  points.clear();
  S.runs.clear();
  for (int e = 0; e < m; ++e) {
    const int first = element_start_[e], take = take_[static_cast<size_t>(e)];
    if (take == 0) continue;
    S.runs.push_back(static_cast<int>(points.size()));
    points.insert(points.end(), element_points_.begin() + first, element_points_.begin() + first + take);
  }
  const size_t tail = points.size();
  for (Eigen::Index p : unbounded_) points.push_back(p);
  const interp::Embedding& emb = deformer_->embedding();
  for (size_t i = 0; i < slips_.size(); ++i) {  // friction energy is never 0
    const Eigen::Index p = slips_[i].point;
    if (slip_first_[static_cast<size_t>(p)] == static_cast<int>(i) && in_hull(emb, p) && !near_[static_cast<size_t>(emb.element(p))])
      points.push_back(p);
  }
  for (size_t i = tail; i < points.size(); ++i)
    if (i == tail || emb.element(points[i]) != emb.element(points[i - 1])) S.runs.push_back(static_cast<int>(i));
  S.runs.push_back(static_cast<int>(points.size()));
}

}  // namespace mbi::pipeline
