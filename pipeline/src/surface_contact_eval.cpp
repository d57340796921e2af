// SurfaceContact's per-point passes (surface_contact.hpp): the candidates' positions, terms,
// gradient, Hessian blocks and product, the cap and the line. Each pass runs on the library's
// threads and writes one result per point; sums are taken per point or per element run in a
// fixed order, so results do not depend on the thread count.
#include <mbi/error.hpp>
#include <mbi/interp/adjoint.hpp>
#include <mbi/interp/parallel.hpp>
#include <mbi/pipeline/contact_laws.hpp>
#include <mbi/pipeline/surface_contact.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace mbi::pipeline {
namespace {

constexpr long long kBlock = 512;  // points per block of a parallel pass
constexpr int kBezier = 10;        // Bezier points per element (3D)

using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Strides = Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>;

/// Row-major rows as interp's points (p x 3 in any strides), to write or to read.
Eigen::Map<Eigen::MatrixXd, 0, Strides> as_points(Rows& R) {
  return Eigen::Map<Eigen::MatrixXd, 0, Strides>(R.data(), R.rows(), 3, Strides(1, 3));
}
Eigen::Map<const Eigen::MatrixXd, 0, Strides> as_points(const Rows& R) {
  return Eigen::Map<const Eigen::MatrixXd, 0, Strides>(R.data(), R.rows(), 3, Strides(1, 3));
}

}  // namespace

void SurfaceContact::evaluate(const interp::BezierPoints& B, const std::vector<Eigen::Index>& points, Rows3& out) const {
  out.resize(static_cast<Eigen::Index>(points.size()), 3);
  interp::evaluate(B, deformer_->embedding(), points, as_points(out), deformer_->options().threads);
}

const SurfaceContact::Sample& SurfaceContact::sample(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  check_size(x);
  if (at_.valid && at_.x == x) return at_;
  terms_valid_ = at_.valid = false;
  if (moved_sample(x)) return at_;
  at_.B = deformer_->bezier(nodes(x));
  gather(at_.B, Eigen::VectorXd::Zero(deformer_->elements()), at_);
  evaluate(at_.B, at_.points, at_.P);
  ++counts_.evaluations;
  counts_.candidates += static_cast<long long>(at_.points.size());
  at_.x = x;
  at_.valid = true;
  return at_;
}

bool SurfaceContact::moved_sample(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const bool taken = line_taken_ && along_.valid;
  line_taken_ = false;
  if (!taken) return false;
  const double s = line_fraction_;
  // the simulator's x + h (v + s delta) against x + s (h delta): the same to round-off
  const double slack = 1e-12 * (diagonal_ + x.cwiseAbs().maxCoeff());
  if (!(((along_.x + s * along_.dx) - x).cwiseAbs().maxCoeff() <= slack)) return false;
  at_.B = along_.B + s * along_.BD;
  at_.points = along_.points;
  at_.runs = along_.runs;
  at_.P = along_.P + s * along_.D;
  ++counts_.evaluations;
  counts_.candidates += static_cast<long long>(at_.points.size());
  at_.x = x;
  at_.valid = true;
  return true;
}

void SurfaceContact::positions_at_x(bool kept, Sample& S) const {
  if (!kept) return evaluate(S.B, S.points, S.P);
  // a point's evaluation is its own: the rows at_ has are copied, the others evaluated
  for (size_t j = 0; j < at_.points.size(); ++j) row_of_[static_cast<size_t>(at_.points[j])] = static_cast<int>(j);
  std::vector<Eigen::Index> fresh, fresh_rows;
  for (size_t i = 0; i < S.points.size(); ++i)
    if (row_of_[static_cast<size_t>(S.points[i])] < 0) {
      fresh.push_back(S.points[i]);
      fresh_rows.push_back(static_cast<Eigen::Index>(i));
    }
  Rows3 F;
  evaluate(S.B, fresh, F);
  S.P.resize(static_cast<Eigen::Index>(S.points.size()), 3);
  for (size_t i = 0; i < S.points.size(); ++i)
    if (const int j = row_of_[static_cast<size_t>(S.points[i])]; j >= 0) S.P.row(static_cast<Eigen::Index>(i)) = at_.P.row(j);
  for (size_t k = 0; k < fresh.size(); ++k) S.P.row(fresh_rows[k]) = F.row(static_cast<Eigen::Index>(k));
  for (Eigen::Index p : at_.points) row_of_[static_cast<size_t>(p)] = -1;
}

const SurfaceContact::Sample& SurfaceContact::sample(const Eigen::Ref<const Eigen::VectorXd>& x,
                                                     const Eigen::Ref<const Eigen::VectorXd>& dx) const {
  check_size(x);
  check_size(dx);
  if (along_.valid && along_.x == x && along_.dx == dx) return along_;
  along_.valid = false;
  const bool kept = at_.valid && at_.x == x;
  along_.B = kept ? at_.B : deformer_->bezier(nodes(x));
  along_.BD = deformer_->bezier(nodes(dx));
  const interp::BezierPoints& BD = along_.BD;
  // A point moves by at most its element's largest Bezier move; the cap needs 0.9 of its room
  // above -max_depth to reach past it before it acts (contact::advance), the line the move itself.
  const int m = deformer_->elements();
  const Eigen::Index K = BD.rows() / m;
  Eigen::VectorXd reach(m);
  for (int e = 0; e < m; ++e) reach(e) = BD.middleRows(e * K, K).rowwise().norm().maxCoeff() / 0.9;
  gather(along_.B, reach, along_);
  evaluate(BD, along_.points, along_.D);
  positions_at_x(kept, along_);
  const size_t C = colliders_.size();
  const bool capped = started_ && !std::isinf(max_depth_);
  const long long rows = static_cast<long long>(along_.points.size());
  std::vector<double> caps(static_cast<size_t>(rows), 1.0);
  std::vector<char> near(static_cast<size_t>(rows), 0);
  // one pass: the cap's advance and whether the point can touch along the line
  interp::parallel_for(rows, kBlock, [&](long long b, long long e) {
    for (long long i = b; i < e; ++i) {
      const Eigen::Index p = along_.points[static_cast<size_t>(i)];
      const Eigen::Vector3d q = along_.P.row(i).transpose(), dq = along_.D.row(i).transpose();
      // d(q + s dq) >= d(q) - L |dq| for s in [0, 1]; the margin covers W (x + s dx) != q + s W dx
      const double line_reach = dq.norm() + 1e-6 * (diagonal_ + q.norm() + dq.norm());
      bool close = slip_first_[static_cast<size_t>(p)] >= 0;  // friction energy is never 0
      double s = 1.0;
      for (size_t c = 0; c < C; ++c) {
        const double d = distance(c, q).value;
        close = close || d < lipschitz_[c] * line_reach;
        if (capped && !std::isinf(depth(p, c))) s = std::min(s, contact::advance(posed_[c], q, dq, time_, max_depth_, d));
      }
      caps[static_cast<size_t>(i)] = s;
      near[static_cast<size_t>(i)] = close;
    }
  }, deformer_->options().threads);
  along_.cap = 1.0;
  along_.near.clear();
  for (size_t i = 0; i < caps.size(); ++i) {
    along_.cap = std::min(along_.cap, caps[i]);
    if (near[i]) along_.near.push_back(static_cast<Eigen::Index>(i));
  }
  ++counts_.moves;
  counts_.move_candidates += rows;
  along_.x = x;
  along_.dx = dx;
  along_.valid = true;
  return along_;
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

SurfaceContact::Term SurfaceContact::term(Eigen::Index p, const Eigen::Vector3d& q, bool full) const {
  Term t;
  for (size_t c = 0; c < colliders_.size(); ++c) {
    const Distance d = distance(c, q);
    if (d.value >= 0) continue;
    const contact::Law law = contact::normal_energy(d.value, stiffness_, depth(p, c));
    t.energy += law.value;
    t.active = true;
    if (!full) continue;
    t.gradient += law.slope * d.normal;
    t.hessian.noalias() += law.curvature * d.normal * d.normal.transpose();
  }
  for (size_t slip = static_cast<size_t>(std::max(slip_first_[static_cast<size_t>(p)], 0));
       slip_first_[static_cast<size_t>(p)] >= 0 && slip < slips_.size() && slips_[slip].point == p; ++slip) {
    const Slip& s = slips_[slip];
    const Eigen::Vector2d u = s.tangent.transpose() * (q - s.anchor);
    const double y = u.norm();
    t.energy += s.weight * contact::friction_f0(y, smoothing_);
    t.active = true;
    if (!full) continue;
    t.gradient.noalias() += (s.weight * contact::friction_f1_over_y(y, smoothing_)) * (s.tangent * u);
    t.hessian.noalias() += s.tangent * (s.weight * contact::friction_hessian(u, smoothing_)) * s.tangent.transpose();
  }
  return t;
}

const std::vector<SurfaceContact::Term>& SurfaceContact::terms(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const Sample& S = sample(x);  // forgets the terms when x changes
  if (terms_valid_) return terms_;
  const long long rows = static_cast<long long>(S.points.size());
  terms_.resize(S.points.size());
  active_.resize(S.points.size());
  interp::parallel_for(rows, kBlock, [&](long long b, long long e) {
    for (long long i = b; i < e; ++i) {
      terms_[static_cast<size_t>(i)] = term(S.points[static_cast<size_t>(i)], S.P.row(i).transpose());
      active_[static_cast<size_t>(i)] = terms_[static_cast<size_t>(i)].active;
    }
  }, deformer_->options().threads);
  terms_valid_ = true;
  active_rows_.clear();
  active_points_.clear();
  for (size_t i = 0; i < active_.size(); ++i)
    if (active_[i]) {
      active_rows_.push_back(i);
      active_points_.push_back(S.points[i]);
    }
  counts_.active += static_cast<long long>(active_rows_.size());
  active_elements_.clear();
  active_vertices_.clear();
  const Eigen::MatrixXi& T = deformer_->elements_matrix();
  for (Eigen::Index p : active_points_) active_elements_.push_back(deformer_->embedding().element(p));
  std::sort(active_elements_.begin(), active_elements_.end());
  active_elements_.erase(std::unique(active_elements_.begin(), active_elements_.end()), active_elements_.end());
  for (int e : active_elements_)
    for (Eigen::Index k = 0; k < T.cols(); ++k) active_vertices_.push_back(T(e, k));
  std::sort(active_vertices_.begin(), active_vertices_.end());
  active_vertices_.erase(std::unique(active_vertices_.begin(), active_vertices_.end()), active_vertices_.end());
  return terms_;
}

double SurfaceContact::energy(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  double E = 0.0;
  for (const Term& t : terms(x))
    if (t.active) E += t.energy;
  return E;
}

void SurfaceContact::add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                                  Eigen::Ref<Eigen::VectorXd> gradient) const {
  const std::vector<Term>& T = terms(x);
  if (active_rows_.empty()) return;  // no term: no solve
  Rows3 G(static_cast<Eigen::Index>(active_rows_.size()), 3);
  for (size_t j = 0; j < active_rows_.size(); ++j) G.row(static_cast<Eigen::Index>(j)) = T[active_rows_[j]].gradient.transpose();
  // W^T restricted to the points with a term (the others have zero rows): exact, fact 11
  add_transpose(G, gradient);
}

void SurfaceContact::add_transpose(const Rows3& G, Eigen::Ref<Eigen::VectorXd> out) const {
  const Eigen::MatrixXd& U = deformer_->rest_positions();
  const int m = deformer_->elements();
  Transpose& t = transpose_;  // scratch, sized once
  interp::BezierPoints& GB = t.GB;
  Eigen::MatrixXd &GX = t.GX, &GMX = t.GMX;
  interp::VertexMatrices& GM = t.GM;
  GB.resize(static_cast<Eigen::Index>(m) * kBezier, 3);
  GX.resize(U.rows(), 3);
  GMX.resize(U.rows(), 3);
  GM.resize(3 * U.rows(), 3);
  interp::evaluate_transpose(deformer_->embedding(), active_points_, as_points(G), m, GB, deformer_->options().threads);
  // GB is written on the active points' elements only, and read there only; GM is zero outside
  // their vertices
  interp::bezier_transpose(U, deformer_->elements_matrix(), GB, active_elements_, GX, GM);
  if (deformer_->method() == Method::ModifiedBI) deformer_->solver().solve_transpose_vertices(GM, active_vertices_, GMX);
  if (deformer_->method() == Method::Phong) deformer_->phong().M_transpose(GM, GMX);
  if (deformer_->method() != Method::BI) GX += GMX;
  for (Eigen::Index i = 0; i < GX.rows(); ++i) out.segment<3>(3 * i) += GX.row(i).transpose();
}

const interp::BezierPoints& SurfaceContact::active_bezier(const Eigen::MatrixXd& X) const {
  const Eigen::MatrixXd& U = deformer_->rest_positions();
  const Eigen::MatrixXi& T = deformer_->elements_matrix();
  product_B_.resize(T.rows() * kBezier, 3);
  product_M_.resize(3 * U.rows(), 3);
  if (deformer_->method() == Method::ModifiedBI) deformer_->solver().solve_vertices(X, active_vertices_, product_M_);
  else if (deformer_->method() == Method::Phong) deformer_->phong().M(X, product_M_);
  else product_M_.setZero();
  interp::bezier_points(U, T, X, product_M_, active_elements_, product_B_);
  return product_B_;
}

bool SurfaceContact::add_hessian_product(const Eigen::Ref<const Eigen::VectorXd>& x,
                                         const Eigen::Ref<const Eigen::VectorXd>& v,
                                         Eigen::Ref<Eigen::VectorXd> out) const {
  if (deformer_->method() == Method::BI) return false;  // the blocks are W^T K W already
  check_size(v);
  const std::vector<Term>& T = terms(x);
  if (active_rows_.empty()) return true;
  Rows3 G;  // K_p (W v)_p at the points with a term (p is linear in x)
  evaluate(active_bezier(nodes(v)), active_points_, G);
  interp::parallel_for(G.rows(), kBlock, [&](long long b, long long e) {
    for (long long j = b; j < e; ++j) G.row(j) = (T[active_rows_[static_cast<size_t>(j)]].hessian * G.row(j).transpose()).transpose();
  }, deformer_->options().threads);
  add_transpose(G, out);
  return true;
}

void SurfaceContact::hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>& x,
                                    std::vector<sim::NodeBlock>& blocks) const {
  const interp::Embedding& emb = deformer_->embedding();
  const Eigen::MatrixXi& T = deformer_->elements_matrix();
  const std::vector<Term>& terms_at = terms(x);
  const Sample& S = at_;
  // summed per run of one element's points (on the threads), then per element in run order: one
  // block per node pair of a touched element, not per point
  using Blocks = std::array<Eigen::Matrix3d, 10>;
  const long long runs = static_cast<long long>(S.runs.size()) - 1;
  std::vector<Blocks> part(static_cast<size_t>(std::max(runs, 0LL)));
  std::vector<char> touched(part.size(), 0);
  interp::parallel_for(runs, 16, [&](long long b, long long e) {
    for (long long r = b; r < e; ++r) {
      Blocks& P = part[static_cast<size_t>(r)];
      for (Eigen::Matrix3d& M : P) M.setZero();
      for (int i = S.runs[static_cast<size_t>(r)]; i < S.runs[static_cast<size_t>(r) + 1]; ++i) {
        if (!active_[static_cast<size_t>(i)]) continue;
        touched[static_cast<size_t>(r)] = 1;
        const Eigen::Index p = S.points[static_cast<size_t>(i)];
        const Eigen::Matrix3d& H = terms_at[static_cast<size_t>(i)].hessian;
        Eigen::Matrix3d* M = P.data();
        for (int a = 0; a < 4; ++a)
          for (int c = 0; c <= a; ++c) (M++)->noalias() += (emb.bary(p, a) * emb.bary(p, c)) * H;
      }
    }
  }, deformer_->options().threads);
  element_block_.resize(static_cast<size_t>(deformer_->elements()), -1);
  for (long long r = 0; r < runs; ++r) {
    if (!touched[static_cast<size_t>(r)]) continue;
    const int e = emb.element(S.points[static_cast<size_t>(S.runs[static_cast<size_t>(r)])]);
    if (element_block_[static_cast<size_t>(e)] < 0) {
      element_block_[static_cast<size_t>(e)] = static_cast<int>(blocks.size());
      for (int a = 0; a < 4; ++a)
        for (int c = 0; c <= a; ++c) blocks.push_back({T(e, a), T(e, c), Eigen::Matrix3d::Zero()});
    }
    sim::NodeBlock* out = &blocks[static_cast<size_t>(element_block_[static_cast<size_t>(e)])];
    for (const Eigen::Matrix3d& M : part[static_cast<size_t>(r)]) (out++)->value += M;
  }
  for (long long r = 0; r < runs; ++r)
    element_block_[static_cast<size_t>(emb.element(S.points[static_cast<size_t>(S.runs[static_cast<size_t>(r)])]))] = -1;
}

double SurfaceContact::max_step(const Eigen::Ref<const Eigen::VectorXd>& x,
                                const Eigen::Ref<const Eigen::VectorXd>& dx) const {
  if (!started_ || std::isinf(max_depth_)) return 1.0;
  return sample(x, dx).cap;  // p is linear in x: the points move by W dx
}

void SurfaceContact::begin_line(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& dx) {
  sample(x, dx);
  line_start_ = x;
  line_move_ = dx;
  line_valid_ = true;
}

void SurfaceContact::end_line(double s) {
  line_taken_ = line_valid_ && along_.valid && along_.x == line_start_ && along_.dx == line_move_;
  line_fraction_ = s;
}

double SurfaceContact::energy_along(double s) const {
  if (!line_valid_) throw Error("contact: energy_along needs begin_line (after the last substep or setting)");
  if (!(s >= 0 && s <= 1)) return energy(line_start_ + s * line_move_);
  const Sample& S = sample(line_start_, line_move_);  // kept from begin_line unless moved elsewhere
  std::vector<double> E(S.near.size(), 0.0);
  interp::parallel_for(static_cast<long long>(S.near.size()), kBlock, [&](long long b, long long e) {
    for (long long i = b; i < e; ++i) {
      const Eigen::Index r = S.near[static_cast<size_t>(i)];
      E[static_cast<size_t>(i)] = term(S.points[static_cast<size_t>(r)], (S.P.row(r) + s * S.D.row(r)).transpose(), false).energy;
    }
  }, deformer_->options().threads);
  double sum = 0.0;
  for (double v : E) sum += v;
  return sum;
}

}  // namespace mbi::pipeline
