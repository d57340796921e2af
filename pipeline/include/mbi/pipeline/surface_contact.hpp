#pragma once
// Contact of embedded points (the dense surface's vertices, or any subset) with analytic
// colliders, as a potential of the control nodes for sim::Simulator (method.md facts 16, 17).
//
//   auto deformer = std::make_shared<pipeline::Deformer>(U, T, contact_points, options);
//   auto contact = std::make_shared<pipeline::SurfaceContact>(deformer, colliders, 1e4);
//   sim.set_potential(contact);
//   per step: sim.step();   // the simulator poses the colliders and lags friction per substep
//
// The dense positions are p = W x (W the deformer's linear map, method.md facts 1 and 11), so
// the energy E(x) = sum_points sum_colliders e(d(p)) + friction (d the collider's signed
// distance, fact 15) has the exact gradient W^T g, g_p = e'(d) n + friction: one
// Deformer::vjp. e is a penalty k d^2 / 2 to second order that grows without bound at the
// depth max_depth() for points that start a substep above it (contact_laws.hpp), and each
// Newton step is capped so that no such point passes that depth (max_step). Friction is IPC's
// lagged, smoothed Coulomb friction. Its Hessian W^T K W is dense for modified-BI; the step gets
// the surrogate (b b^T) (x) K_p per touching point, with b the point's BI weights in its own
// element and K_p the point's 3x3 Hessian: positive semi-definite and inside the FEM's pattern.
// Only the points that can touch are evaluated (broad phase, method.md fact 16): a point lies in
// the convex hull of its element's Bezier points and moves by at most their move, so its distance
// at a substep's start less L times that move bounds it; the others add exactly nothing.
//
// Units: stiffness k in N/m per point; positions and depths in m; friction velocity in m/s;
// energy in J. One SurfaceContact is not for several threads at once (it keeps scratch).
#include <mbi/pipeline/colliders.hpp>
#include <mbi/pipeline/deformer.hpp>
#include <mbi/sim/potential.hpp>

#include <memory>
#include <vector>

namespace mbi::pipeline {

class SurfaceContact : public sim::Potential {
 public:
  /// deformer: 3D, its points are the contact points. colliders: checked (Error naming
  /// "collider i" and the field). stiffness: N/m, finite and > 0. A collider that holds a
  /// contact point of the rest pose (the deformer's control positions, colliders at time 0)
  /// deeper than the default max_depth() is refused: Error "collider i overlaps the model at
  /// rest: contact point j is D m inside".
  SurfaceContact(std::shared_ptr<const Deformer> deformer, std::vector<Collider> colliders,
                 double stiffness);

  /// Time (s) at which the colliders are posed; the simulator sets the end of each substep
  /// (begin_substep_at).
  void set_time(double time);
  /// begin_substep_at(time(), end_time, x, v).
  void begin_substep(double end_time, const Eigen::Ref<const Eigen::VectorXd>& x,
                     const Eigen::Ref<const Eigen::VectorXd>& v) override;
  /// Poses the colliders at end_time and, from the start positions x (3 n): which point and
  /// collider pairs are guarded (signed distance > -max_depth()), and per touching pair with
  /// friction the lagged normal force, tangent basis and anchor (method.md fact 17). With
  /// end_time <= start_time there is no friction in the substep. The start velocities v (3 n)
  /// set how far from the colliders the start evaluates points (fact 16); Error on a size other than 3 n.
  void begin_substep_at(double start_time, double end_time, const Eigen::Ref<const Eigen::VectorXd>& x,
                        const Eigen::Ref<const Eigen::VectorXd>& v) override;
  double time() const { return time_; }
  const std::vector<Collider>& colliders() const { return colliders_; }
  /// Replaces collider i (checked as the constructor's; no rest-overlap check) from the next
  /// evaluation on: a collider moved between steps, as the viewer's drag does. Throws Error on
  /// an index out of range or a bad collider.
  void set_collider(size_t i, const Collider& collider);
  double stiffness() const { return stiffness_; }

  /// Depth (m, > 0) that guarded points never pass: their energy grows without bound there and
  /// max_step keeps them above it. Infinity: the plain penalty k d^2 / 2 and no cap. Default:
  /// 1e-3 of the control mesh's rest bounding-box diagonal. Takes effect at the next substep.
  void set_max_depth(double depth);
  double max_depth() const { return max_depth_; }
  /// IPC's eps_v (m/s, > 0): tangential speeds below it are smoothed (static friction is a
  /// creep at about this speed). Default: 1e-4 control-mesh diagonals per second.
  void set_friction_velocity(double velocity);
  double friction_velocity() const { return friction_velocity_; }
  /// Number of point and collider pairs that carry lagged friction in the current substep.
  int friction_pairs() const { return static_cast<int>(slips_.size()); }

  /// The contact points' positions (p x 3) at node positions x (3 n stacked, as the simulator's).
  Eigen::MatrixXd points(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// Number of contact points (the deformer's points).
  long long contact_points() const { return deformer_->points(); }
  /// Number of contact points inside some collider (signed distance < 0) at x, at time().
  int touching(const Eigen::Ref<const Eigen::VectorXd>& x) const;

  /// What the broad phase evaluated since construction or reset_counts() (method.md fact 16):
  /// per new x (energy, gradient, Hessian) the candidate points and those with a term there;
  /// per move (cap, line) the candidates; per substep start the points evaluated there.
  struct Counts {
    long long evaluations = 0, candidates = 0, active = 0;
    long long moves = 0, move_candidates = 0;
    long long substeps = 0, substep_points = 0;
  };
  const Counts& counts() const { return counts_; }
  void reset_counts() { counts_ = {}; }

  double energy(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                    Eigen::Ref<Eigen::VectorXd> gradient) const override;
  void hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>& x,
                      std::vector<sim::NodeBlock>& blocks) const override;
  /// Adds W^T K W v (K the touching points' 3x3 blocks K_p, those of hessian_blocks) through
  /// the deformer; false for BI, whose blocks are that matrix.
  bool add_hessian_product(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& v,
                           Eigen::Ref<Eigen::VectorXd> out) const override;
  /// The largest fraction (0, 1] of the move x -> x + dx that keeps every guarded point above
  /// -max_depth() on its straight path (p is linear in x), by contact::advance.
  double max_step(const Eigen::Ref<const Eigen::VectorXd>& x,
                  const Eigen::Ref<const Eigen::VectorXd>& dx) const override;
  /// Deforms x and dx once (p(x + s dx) = p(x) + s W dx) and keeps the points that can touch
  /// a collider or carry friction for some s in [0, 1] (the distance is 1-Lipschitz), so that
  /// each energy_along(s) there costs those points only; other s evaluate every point.
  void begin_line(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& dx) override;
  double energy_along(double s) const override;
  /// The next evaluation at x + s dx (to round-off) takes the line's points moved by s: their
  /// positions P + s W dx and the Bezier points B + s B(dx), no new broad phase (the line's
  /// candidates cover every point that can touch for s in [0, 1]).
  void end_line(double s) override;

 private:
  /// Lagged friction of one point against one collider in the current substep.
  struct Slip {
    int point = 0;
    double weight = 0.0;                    ///< mu lambda, N
    Eigen::Matrix<double, 3, 2> tangent;    ///< orthonormal basis of the tangent plane
    Eigen::Vector3d anchor;                 ///< start position moved with the collider, m
  };
  using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  /// The contact points that can matter at x (or on the move x -> x + dx), found from the
  /// element Bezier points (a point lies in their convex hull) and the substep's start, and their
  /// positions W x (and W dx), evaluated from the deformer's embedding without copying its rows.
  struct Sample {
    Eigen::VectorXd x, dx;              // dx empty: positions only
    interp::BezierPoints B;             // at x
    std::vector<Eigen::Index> points;   // by element, then by distance at the substep's start
    std::vector<int> runs;              // starts of the runs of `points` in one element, then their count
    interp::BezierPoints BD;            // a move's: at dx
    Rows3 P, D;                         // W x and W dx at those points, rows as `points`
    double cap = 1.0;                   // a move's: the largest fraction that max_step admits
    std::vector<Eigen::Index> near;     // a move's: the rows that can contribute along it
    bool valid = false;
  };
  const Sample& sample(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// at_ from along_ moved by the line's accepted fraction, when x is that move's end (end_line).
  bool moved_sample(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  const Sample& sample(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& dx) const;
  void check_size(const Eigen::Ref<const Eigen::VectorXd>& x, const char* what = "node positions") const;
  const Eigen::MatrixXd& nodes(const Eigen::Ref<const Eigen::VectorXd>& x) const;  // n x 3 into X_
  /// The points that can come within `reach` (m, per element) of a collider: of the elements
  /// whose Bezier points do, those whose distance at the substep's start is not farther than
  /// their element's Bezier move since then (all of them without a start), and the points
  /// outside every hull and with friction; and their runs by element. Costs the elements and
  /// the points it keeps.
  void gather(const interp::BezierPoints& B, const Eigen::VectorXd& reach, Sample& S) const;
  /// A lower bound of collider k's distance on the hull of an element's Bezier points Be.
  double hull_lower(const Eigen::Ref<const interp::BezierPoints>& Be, size_t k) const;
  /// The last substep's start bounds this one's: per element, how far a collider moved relative
  /// to its points from the last pose (`previous`, s) to time() (shift_), B: the new start.
  void carry_reference(const interp::BezierPoints& B, double previous);
  /// The substep's start (S: its sample, least: per row of S the least distance there): per
  /// element the hull's bound, or (the elements S sampled) its points ordered by a lower bound of
  /// their distance: their own where evaluated, else (carried) the last one less the move since.
  void set_reference(const Sample& S, const std::vector<double>& least, bool carry);
  void index_points();                                          // element_start_ and the rest
  /// W applied to the Bezier points B at `points`, rows as `points` (interp's subset evaluation).
  void evaluate(const interp::BezierPoints& B, const std::vector<Eigen::Index>& points, Rows3& out) const;
  /// S.P from S.B at S.points; kept: S.B is at_.B, whose rows are copied (the same values).
  void positions_at_x(bool kept, Sample& S) const;
  /// Adds W^T G to out (3 n): G one row per point of active_points_ (interp's sums per run of one
  /// element, so the same for every thread count), through their elements and vertices only.
  void add_transpose(const Rows3& G, Eigen::Ref<Eigen::VectorXd> out) const;
  /// The Bezier points at node positions X (n x 3) of the elements of active_points_ (the others'
  /// rows stale): modified-BI solves for M at their vertices only (interp's solve_vertices).
  const interp::BezierPoints& active_bezier(const Eigen::MatrixXd& X) const;
  double depth(Eigen::Index point, size_t collider) const;        // guarded depth or infinity
  /// signed_distance(posed_[c], q, time()): the same values, a plane's from its unit normal kept.
  Distance distance(size_t c, const Eigen::Vector3d& q) const {
    if (posed_[c].shape != ColliderShape::Plane) return signed_distance(posed_[c], q, time_);
    Distance d;
    d.normal = unit_normal_[c];
    d.value = d.normal.dot(q - posed_[c].point);
    return d;
  }
  /// One point's energy (J), gradient (N) and Hessian or PSD surrogate (N/m) at position q, all
  /// colliders and its slips; the energy alone unless `full`.
  struct Term {
    double energy = 0.0;
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
    Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
    bool active = false;
  };
  Term term(Eigen::Index point, const Eigen::Vector3d& q, bool full = true) const;
  /// The terms at x, one per point of sample(x) (kept until x, the time or the substep changes);
  /// active_ flags those with a term.
  const std::vector<Term>& terms(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  void forget() { terms_valid_ = line_valid_ = line_taken_ = at_.valid = along_.valid = false; }  // after a change of time or law

  std::shared_ptr<const Deformer> deformer_;
  std::vector<Collider> colliders_;
  std::vector<Collider> posed_;  // colliders_ at time_, static: the same distances, cheaper
  std::vector<Eigen::Vector3d> unit_normal_;  // posed_'s normals over their length (planes)
  // how fast each collider's distance can change per unit moved (1: exact; a mesh's level set more)
  std::vector<double> lipschitz_;
  double steepest_ = 1.0;  // their largest
  double stiffness_ = 0.0;
  double time_ = 0.0;
  double diagonal_ = 0.0;  // control mesh, rest
  double max_depth_ = 0.0;
  double friction_velocity_ = 0.0;
  double smoothing_ = 0.0;        // eps_v h of the current substep, m
  bool started_ = false;          // a substep has begun: guards apply
  std::vector<char> unguarded_;   // point-major, per collider: started the substep deeper than max_depth
  std::vector<size_t> unguarded_set_;  // its entries that are 1
  std::vector<Slip> slips_;       // a point's slips one after another
  std::vector<int> slip_first_;   // per point, its first slip or -1
  std::vector<int> element_start_, element_points_;  // per element, its points inside the hull
  std::vector<Eigen::Index> unbounded_;              // points with a negative barycentric coordinate
  // The substep's start (set_reference): Bezier points; per element (`exact_` 0) its hull's least
  // distance to the colliders, or (`exact_` 1) its points in element_points_ ordered by a lower
  // bound of their least distance, that bound plus offset_ in start_distance_ (aligned with it).
  bool reference_ = false;
  interp::BezierPoints reference_B_;
  std::vector<double> element_distance_, start_distance_, offset_;
  std::vector<double> shift_;  // per element, carry_reference's collider move, m (0 within a substep)
  std::vector<char> exact_;
  mutable std::vector<char> near_;                    // per element, gather's last hull test
  mutable std::vector<int> take_;                     // per element, gather's points taken
  mutable std::vector<int> row_of_;                   // per point, a sample's row or -1 (scratch)
  mutable std::vector<int> element_block_;            // per element, hessian_blocks' scratch (-1)
  mutable Eigen::MatrixXd X_;
  mutable Sample at_, along_;          // x of the last evaluation; x and dx of the last move
  mutable std::vector<Term> terms_;    // at at_.x, per point of at_
  mutable std::vector<char> active_;   // terms_[i].active
  mutable std::vector<size_t> active_rows_;          // the rows i of at_ with terms_[i].active
  mutable std::vector<Eigen::Index> active_points_;  // their points
  mutable std::vector<int> active_elements_, active_vertices_;  // theirs, ascending
  mutable interp::BezierPoints product_B_;           // active_bezier's result
  mutable interp::VertexMatrices product_M_;         // and its M
  struct Transpose {                                 // add_transpose's scratch
    interp::BezierPoints GB;
    Eigen::MatrixXd GX, GMX;
    interp::VertexMatrices GM;
  };
  mutable Transpose transpose_;
  mutable bool terms_valid_ = false;
  mutable bool line_taken_ = false;  // end_line's fraction of along_'s move awaits moved_sample
  double line_fraction_ = 0.0;
  Eigen::VectorXd line_start_, line_move_;  // begin_line's x and dx
  bool line_valid_ = false;
  mutable Counts counts_;
};

}  // namespace mbi::pipeline
