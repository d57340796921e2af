#include "block_rows.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/sim/rigid_pose.hpp>
#include <mbi/sim/simulator.hpp>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cstdio>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <string>

namespace mbi::sim {
namespace {

std::string vec_str(const Eigen::Vector3d& v) {
  return "(" + std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " +
         std::to_string(v.z()) + ")";
}

void check_params(const Parameters& p) {
  auto bad = [](const std::string& what) { throw Error("parameter " + what); };
  if (!std::isfinite(p.dt) || p.dt <= 0) bad("dt must be finite and > 0 s");
  if (p.substeps < 1) bad("substeps must be >= 1");
  if (!p.gravity.allFinite()) bad("gravity must be finite");
  if (!std::isfinite(p.mass_damping) || p.mass_damping < 0) bad("mass_damping must be >= 0");
  if (!std::isfinite(p.stiffness_damping) || p.stiffness_damping < 0)
    bad("stiffness_damping must be >= 0");
  if (p.newton_iterations < 1) bad("newton_iterations must be >= 1");
  if (!std::isfinite(p.newton_tolerance) || p.newton_tolerance < 0)
    bad("newton_tolerance must be >= 0");
  if (!std::isfinite(p.pcg_tolerance) || p.pcg_tolerance <= 0 || p.pcg_tolerance >= 1)
    bad("pcg_tolerance must lie in (0, 1)");
  if (p.pcg_max_iterations < 1) bad("pcg_max_iterations must be >= 1");
  if (!std::isfinite(p.max_energy) || p.max_energy < 0) bad("max_energy must be >= 0");
  if (p.ground) {
    if (!p.ground_plane.normal.allFinite() || p.ground_plane.normal.norm() == 0)
      bad("ground_plane.normal must be finite and non-zero");
    if (!std::isfinite(p.ground_plane.offset)) bad("ground_plane.offset must be finite");
    if (!(p.ground_plane.friction >= 0 && p.ground_plane.friction <= 1))
      bad("ground_plane.friction must lie in [0, 1]");
  }
}

struct Elem {
  std::array<int, 4> node;
  Eigen::Matrix<double, 3, 4> grad;  // TetRest::grad
  double volume;
  Lame lame;
  // blk[a][b]: index of the stored 3x3 node block (rows of node a, columns of node b) when
  // node a >= node b; -1 when block (b, a) is stored instead.
  std::array<std::array<int, 4>, 4> blk;
};

// What the assembly's element pass leaves for its node pass, per element.
struct ElementTerms {
  std::vector<double> energy;                      // J
  std::vector<Eigen::Matrix<double, 3, 4>> force;  // N, a column a corner
  std::vector<Eigen::Matrix<double, 3, 4>> RG;     // R grad, for the stiffness blocks
  std::vector<Eigen::Matrix<double, 3, 4>> Kv;     // K_e v, a column a corner (when asked)
  void resize(size_t m, bool product) {
    energy.resize(m);
    force.resize(m);
    RG.resize(m);
    Kv.resize(product ? m : 0);
  }
};

constexpr long long kElementBlock = 64;  // elements per block of the element loops

// cK K_ac of the element's warped stiffness (add_warped_tet_block's), RG = R grad: summed in
// registers so that the global block takes one addition an element.
inline Eigen::Matrix3d stiffness_block(const Elem& el, const Eigen::Matrix<double, 3, 4>& RG, double cK, int a, int c) {
  const double sl = cK * el.volume * el.lame.lambda, sm = cK * el.volume * el.lame.mu;
  Eigen::Matrix3d K;
  K.noalias() = (sl * RG.col(a)) * RG.col(c).transpose();
  K.noalias() += (sm * RG.col(c)) * RG.col(a).transpose();
  K.diagonal().array() += sm * el.grad.col(a).dot(el.grad.col(c));
  return K;
}

// The element's deformation gradient F = x_c grad^T at the stacked positions x (3n).
Eigen::Matrix3d deformation_gradient(const Elem& el, const Eigen::VectorXd& x) {
  Eigen::Matrix<double, 3, 4> xc;
  for (int a = 0; a < 4; ++a) xc.col(a) = x.segment<3>(3 * el.node[a]);
  Eigen::Matrix3d F;
  F.noalias() = xc * el.grad.transpose();
  return F;
}

/// Polar rotation of F by Newton iterations from a nearby rotation R (the element's rotation of
/// the previous assembly): with S = R^T F, solve (tr(S) I - S) w = axial(S - S^T) and update
/// R <- R cay(w) (Cayley, exactly orthogonal) until S is symmetric to round-off. tr(S) I - S is
/// positive definite exactly when R is near the maximiser of tr(R^T F) over rotations, i.e. the
/// proper polar rotation (also for inverted F whose two larger singular values dominate).
/// Returns false (caller falls back to the closed form) if that fails or does not converge.
bool refine_rotation(const Eigen::Matrix3d& F, Eigen::Matrix3d& R) {
  const double fnorm = F.norm();
  for (int it = 0; it < 4; ++it) {
    Eigen::Matrix3d S;
    S.noalias() = R.transpose() * F;
    const Eigen::Vector3d a(S(2, 1) - S(1, 2), S(0, 2) - S(2, 0), S(1, 0) - S(0, 1));
    if (a.norm() <= 1e-14 * fnorm) return true;
    const double tr = S.trace();
    Eigen::Matrix3d G = -0.5 * (S + S.transpose());
    G.diagonal().array() += tr;
    // Positive definiteness by leading minors, with a relative margin.
    const double m1 = G(0, 0), m2 = G(0, 0) * G(1, 1) - G(0, 1) * G(1, 0), m3 = G.determinant();
    const double g = std::abs(tr) + 1e-300;
    if (!(m1 > 1e-6 * g && m2 > 1e-6 * g * g && m3 > 1e-6 * g * g * g)) return false;
    Eigen::Vector3d c;
    c.noalias() = 0.5 * (G.inverse() * a);
    Eigen::Matrix3d C;
    C << 0, -c.z(), c.y(), c.z(), 0, -c.x(), -c.y(), c.x(), 0;
    Eigen::Matrix3d Q = Eigen::Matrix3d::Identity();
    Q.noalias() += (2.0 / (1.0 + c.squaredNorm())) * (C + C * C);
    const Eigen::Matrix3d Rn = R * Q;
    R = Rn;
  }
  Eigen::Matrix3d S;
  S.noalias() = R.transpose() * F;
  const Eigen::Vector3d a(S(2, 1) - S(1, 2), S(0, 2) - S(2, 0), S(1, 0) - S(0, 1));
  return a.norm() <= 1e-12 * fnorm;
}

struct Kinematic {
  std::vector<int> nodes;
  Eigen::MatrixXd p0;  // k x 3
  RigidMotion motion;
  Eigen::Vector3d position(int k, double t) const {
    return rigid_pose(motion, t).apply(p0.row(k).transpose(), motion.center);
  }
};

struct PointForce {
  int element;
  Eigen::Vector4d bary;
  Eigen::Vector3d force;
};

struct Poke {
  int element;
  Eigen::Vector4d bary;
  Eigen::Vector3d target;
  double stiffness;
};

}  // namespace

struct Simulator::Impl {
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  Parameters params;
  std::vector<Elem> elems;
  Eigen::VectorXd mass;      // n
  Eigen::VectorXd mass_dof;  // 3n
  int n = 0;
  double total_volume = 0.0;
  double energy_limit = 0.0;
  double bbox_diagonal = 0.0;

  // state
  Eigen::VectorXd x, v;  // 3n
  Eigen::MatrixXd Xout, Vout;
  double t = 0.0;
  long steps = 0;

  // handles
  int next_id = 0;
  std::map<int, Kinematic> kinematic;
  std::map<int, PointForce> forces;
  std::map<int, Poke> pokes;
  std::vector<int> owner;  // per node: kinematic handle id or -1
  std::vector<char> constrained_dof;
  std::vector<int> zero_blocks;  // off-diagonal blocks touching a constrained node
  bool constraints_dirty = true;

  // The loop of the element and node loops (set_parallel_for); empty: this thread.
  ParallelFor parallel;
  // Node i's elements: incidence[incidence_start[i] ...) = 4 e + its corner, ascending e.
  std::vector<int> incidence_start, incidence;

  // linear algebra
  // System matrix in symmetric 3x3 block form: node j's column holds blocks
  // [blk_outer[j], blk_outer[j+1]), the diagonal block first, then rows i > j (blk_row).
  std::vector<int> blk_outer, blk_row;
  std::vector<Eigen::Matrix3d> blk_val;
  Eigen::SparseMatrix<double> A;  // the same, lower triangle in scalar CSC, for LDLT
  std::vector<int> csc_from_blk;  // CSC value p = blk_val[q / 9].data()[q % 9]
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;
  bool ldlt_analysed = false;
  std::vector<Eigen::Matrix3d> block_inv;  // PCG block-Jacobi preconditioner, per node
  detail::BlockRows rows;                  // the same matrix in full rows, for products
  bool rows_stale = true, inverse_stale = true;  // blk_val changed since rows / block_inv
  Eigen::VectorXd pcg_r, pcg_z, pcg_p, pcg_q;
  LinearSolver used_solver = LinearSolver::LDLT;
  static constexpr int kAutoPcgDofs = 600;
  bool auto_fell_back = false;  // Auto: PCG failed once (ill-conditioned), LDLT from then on
  // PCG warm start: solutions of the first Newton iteration of the last two substeps.
  Eigen::VectorXd guess1, guess2;
  int newton_index = -1;  // Newton iteration of the current solve; -1: static solve
  double inner_tolerance = 0.0;  // PCG's relative residual when > 0 (else pcg_tolerance)
  // Each preconditioner solve of exact_step (PCG on the blocks' system) to 1e-3 unless
  // pcg_tolerance is looser: the same Newton iterations for fewer PCG iterations
  // (bench/results/contact.md)
  static constexpr double kInnerRelative = 1e-3;
  double inner_relative() const { return std::max(kInnerRelative, params.pcg_tolerance); }
  // The potential gave its exact Hessian product at the last step that asked (exact_step):
  // Newton's own solve is then that step's first preconditioner solve.
  bool gives_product = false;

  // element rotations of the last assembly (warm start of the next)
  std::vector<Eigen::Matrix3d> rot;
  bool have_rot = false;

  // scratch
  Eigen::VectorXd f_el, f_ext, Kv, r, delta;
  ElementTerms terms;
  double last_elastic = 0.0;

  // extra potential (fact 14) and its per-iteration scratch
  std::shared_ptr<Potential> potential;
  std::vector<NodeBlock> pot_blocks;
  Eigen::VectorXd pot_grad, trial, x_trial;
  int halvings = 0;                 // line-search halvings of the current step
  Eigen::VectorXd cg_d, cg_res, cg_z, cg_z_old, cg_p, cg_q, cg_hv;  // exact_step's scratch
  std::vector<double> phi_history;  // incremental potential of the last substep
  // With a potential, Newton's first guess extrapolates the last substep's change of velocity:
  // its start velocity and length (0: none, after a reset or a state set from outside).
  Eigen::VectorXd last_v;
  double last_h = 0.0;

  void build(const Eigen::Ref<const Eigen::MatrixXd>& U_, const Eigen::Ref<const Eigen::MatrixXi>& T_,
             const Material& material, const std::vector<Material>& per_element);
  void build_pattern();
  void build_incidence();
  void update_constraints();
  void resolve_solver();
  void sync_out() {
    Xout = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(x.data(), n, 3);
    Vout = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(v.data(), n, 3);
  }
  Eigen::Vector3d node(const Eigen::VectorXd& q, int i) const { return q.segment<3>(3 * i); }
  Eigen::Vector3d material_point(const Eigen::VectorXd& q, int e, const Eigen::Vector4d& b) const {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) p += b(a) * node(q, elems[e].node[a]);
    return p;
  }
  void check_element_bary(int element, const Eigen::Vector4d& bary) const;
  int block_index(int i, int j) const;  // stored block of the pair, -1 outside the pattern
  // The elastic energy at xe; with `near`, each element's rotation refined from its entry there
  // (the same polar rotation to round-off, a few times cheaper than the closed form).
  double elastic_energy_at(const Eigen::VectorXd& xe, const std::vector<Eigen::Matrix3d>* near = nullptr) const;
  double poke_energy(const Eigen::VectorXd& xe) const;
  // Backward Euler's incremental potential at velocity vk (positions x + h vk into xs), and
  // the same without the potential's energy.
  double incremental(const Eigen::VectorXd& vk, double h, Eigen::VectorXd& xs) const;
  double incremental_own(const Eigen::VectorXd& vk, double h, Eigen::VectorXd& xs) const;
  // Adds c times the potential's Hessian blocks at xe to the system; empty or why not.
  std::string add_potential_hessian(const Eigen::VectorXd& xe, double c);
  // The potential's admissible fraction of moving the velocity from vk by dv (max_step).
  double admissible(const Eigen::VectorXd& vk, const Eigen::VectorXd& dv, double h);
  // Moves vk along delta by the largest of s, s/2, s/4, ... (s the admissible fraction) that
  // satisfies Armijo's rule on the incremental potential phi (updated); false when none does.
  bool line_search(Eigen::VectorXd& vk, double h, double& phi);
  // With a potential that gives its exact Hessian product: the Newton step delta (the system's
  // solution on entry, to the inner tolerance when gives_product) replaced by conjugate
  // gradients on the system with that Hessian, from 0, preconditioned by the system (its first
  // direction is delta); c = h^2. Without: unchanged.
  bool exact_step(const Eigen::VectorXd& xe, double c, std::string& why, int& iterations);
  // out = (A - c S + c H) v on the free dofs (S the potential's blocks in A, H its exact
  // Hessian); false when the potential gives no product.
  bool exact_product(const Eigen::VectorXd& xe, double c, const Eigen::VectorXd& v, Eigen::VectorXd& out);
  // out = A^-1 b with the matrix of the last solve (LDLT: its factor, PCG: from 0).
  bool solve_again(const Eigen::VectorXd& b, Eigen::VectorXd& out, std::string& why, int& iterations);
  void check_nodes(const std::vector<int>& nodes) const;

  // Assembles at positions xe: elastic forces into f_el, A = cM M + cK K_el + cP K_poke (lower,
  // constrained rows/cols zeroed), and, when vd is non-null, Kv = K_el vd. Returns elastic energy.
  double assemble(const Eigen::VectorXd& xe, double cM, double cK, double cP,
                  const Eigen::VectorXd* vd);
  // The element loop of assemble(), on caller-owned outputs (so that the const accessors can
  // run it on copies): element rotations at xe into rots (refined from the values in rots when
  // warm, else from the closed form), elastic forces into f (resized), cK K_el added to the
  // lower node blocks `blocks`, and, when vd is non-null, K_el vd into Kvd (resized). Returns
  // the elastic energy. K_el = sum_e R_e K_e R_e^T, the warped stiffness.
  double assemble_elastic(const Eigen::VectorXd& xe, double cK, const Eigen::VectorXd* vd,
                          bool warm, std::vector<Eigen::Matrix3d>& rots,
                          std::vector<Eigen::Matrix3d>& blocks, Eigen::VectorXd& f,
                          Eigen::VectorXd& Kvd, ElementTerms& et) const;
  // assemble_elastic's element pass for element e (its rotation in R) and its node pass for
  // node j (f, Kvd when non-null and the blocks of column j, summed in element order).
  void element_terms(size_t e, const Eigen::VectorXd& xe, const Eigen::VectorXd* vd, bool warm,
                     Eigen::Matrix3d& R, ElementTerms& et) const;
  void node_terms(int j, double cK, const ElementTerms& et, std::vector<Eigen::Matrix3d>& blocks,
                  Eigen::VectorXd& f, Eigen::VectorXd* Kvd) const;
  // Without a loop: element e's parts added at once (the node pass's sums in the same order).
  void add_element(size_t e, double cK, const ElementTerms& et, std::vector<Eigen::Matrix3d>& blocks,
                   Eigen::VectorXd& f, Eigen::VectorXd* Kvd) const;
  void external_forces();                                   // gravity + point forces -> f_ext
  void add_poke_forces(const Eigen::VectorXd& xe, Eigen::VectorXd& f) const;
  bool solve(std::string& why, int& iterations);            // A delta = r
  bool pcg_solve(std::string& why, int& iterations);
  // The block-Jacobi inverses of the current matrix (false and why when a block is singular).
  bool invert_diagonal(std::string& why);
  // out = A v with the current matrix (lower blocks); returns v . out when `dot`.
  double product(const Eigen::VectorXd& v, Eigen::VectorXd& out, bool dot);
  // PCG's update of nodes [b, e): delta += alpha p, pcg_r -= alpha pcg_q, then pcg_z from
  // pcg_r; returns r . r and r . z over them.
  std::array<double, 2> pcg_update(double alpha, long long b, long long e);
  void prescribed(double time, Eigen::VectorXd& pos) const; // kinematic positions into pos
  std::string substep(double h, int& newton, int& iters, double& t_asm, double& t_solve);
  void ground();
};

void Simulator::Impl::build(const Eigen::Ref<const Eigen::MatrixXd>& U_,
                            const Eigen::Ref<const Eigen::MatrixXi>& T_, const Material& material,
                            const std::vector<Material>& per_element) {
  const MeshRest rest = mesh_rest(U_, T_, material, per_element);
  U = U_;
  T = T_;
  n = static_cast<int>(U.rows());
  mass = lumped_masses(rest, T, n);
  for (int i = 0; i < n; ++i)
    if (!(mass(i) > 0))
      throw Error("node " + std::to_string(i) +
                  " belongs to no element (it would have no mass)");
  mass_dof.resize(3 * n);
  for (int i = 0; i < n; ++i) mass_dof.segment<3>(3 * i).setConstant(mass(i));
  elems.resize(T.rows());
  double max_E = 0.0;
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    Elem& el = elems[e];
    for (int a = 0; a < 4; ++a) el.node[a] = T(e, a);
    el.grad = rest.tets[e].grad;
    el.volume = rest.tets[e].volume;
    el.lame = rest.lame[e];
    total_volume += el.volume;
    const Material& m = per_element.empty() ? material : per_element[e];
    max_E = std::max(max_E, m.youngs_modulus);
  }
  energy_limit = 1e6 * max_E * total_volume;
  bbox_diagonal = (U.colwise().maxCoeff() - U.colwise().minCoeff()).norm();
  x.resize(3 * n);
  for (int i = 0; i < n; ++i) x.segment<3>(3 * i) = U.row(i).transpose();
  v = Eigen::VectorXd::Zero(3 * n);
  owner.assign(n, -1);
  constrained_dof.assign(3 * n, 0);
  rot.assign(elems.size(), Eigen::Matrix3d::Identity());
  build_incidence();
  build_pattern();
  resolve_solver();
  sync_out();
}

void Simulator::Impl::build_incidence() {
  incidence_start.assign(n + 1, 0);
  for (const Elem& el : elems)
    for (int a = 0; a < 4; ++a) ++incidence_start[el.node[a] + 1];
  for (int i = 0; i < n; ++i) incidence_start[i + 1] += incidence_start[i];
  incidence.resize(4 * elems.size());
  std::vector<int> next(incidence_start.begin(), incidence_start.end() - 1);
  for (size_t e = 0; e < elems.size(); ++e)
    for (int a = 0; a < 4; ++a) incidence[next[elems[e].node[a]]++] = static_cast<int>(4 * e) + a;
}

void Simulator::Impl::build_pattern() {
  // Lower node adjacency: for node j, the nodes i > j sharing an element.
  std::vector<std::vector<int>> lower(n);
  for (const Elem& el : elems)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        if (el.node[a] > el.node[b]) lower[el.node[b]].push_back(el.node[a]);
  for (auto& l : lower) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
  }
  blk_outer.assign(n + 1, 0);
  for (int j = 0; j < n; ++j) blk_outer[j + 1] = blk_outer[j] + 1 + static_cast<int>(lower[j].size());
  blk_row.resize(blk_outer[n]);
  for (int j = 0; j < n; ++j) {
    blk_row[blk_outer[j]] = j;
    std::copy(lower[j].begin(), lower[j].end(), blk_row.begin() + blk_outer[j] + 1);
  }
  blk_val.assign(blk_outer[n], Eigen::Matrix3d::Zero());
  for (Elem& el : elems)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const int i = el.node[a], j = el.node[b];
        if (i < j) {
          el.blk[a][b] = -1;
        } else if (i == j) {
          el.blk[a][b] = blk_outer[j];
        } else {
          const auto& lj = lower[j];
          const int rank = static_cast<int>(std::lower_bound(lj.begin(), lj.end(), i) - lj.begin());
          el.blk[a][b] = blk_outer[j] + 1 + rank;
        }
      }
  // Scalar CSC (lower triangle) of the same matrix for the direct solver.
  const int N = 3 * n;
  std::vector<int> outer(N + 1, 0);
  for (int j = 0; j < n; ++j)
    for (int l = 0; l < 3; ++l)
      outer[3 * j + l + 1] = outer[3 * j + l] + (3 - l) + 3 * static_cast<int>(lower[j].size());
  const int nnz = outer[N];
  std::vector<int> inner(nnz);
  csc_from_blk.resize(nnz);
  for (int j = 0; j < n; ++j)
    for (int l = 0; l < 3; ++l) {
      int p = outer[3 * j + l];
      for (int k = l; k < 3; ++k) {
        inner[p] = 3 * j + k;
        csc_from_blk[p++] = 9 * blk_outer[j] + 3 * l + k;
      }
      for (size_t r = 0; r < lower[j].size(); ++r)
        for (int k = 0; k < 3; ++k) {
          inner[p] = 3 * lower[j][r] + k;
          csc_from_blk[p++] = 9 * (blk_outer[j] + 1 + static_cast<int>(r)) + 3 * l + k;
        }
    }
  A = Eigen::SparseMatrix<double>(N, N);
  A.resizeNonZeros(nnz);
  std::copy(outer.begin(), outer.end(), A.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), A.innerIndexPtr());
  std::fill(A.valuePtr(), A.valuePtr() + nnz, 0.0);
  ldlt_analysed = false;
  rows.build(blk_outer, blk_row);
  rows_stale = inverse_stale = true;
}

void Simulator::Impl::resolve_solver() {
  used_solver = params.solver;
  // Measured (bench/bench_sim.cpp, 2 cores): block-Jacobi PCG wins from about 1K dofs up
  // (2-3x at 1.3K tets, 6-9x at 5K, 40x at 20K); the direct solver wins on tiny meshes.
  if (used_solver == LinearSolver::Auto)
    used_solver = (3 * n >= kAutoPcgDofs && !auto_fell_back) ? LinearSolver::PCG : LinearSolver::LDLT;
  if (used_solver == LinearSolver::LDLT && !ldlt_analysed) {
    ldlt.analyzePattern(A);
    ldlt_analysed = true;
  }
}

void Simulator::Impl::update_constraints() {
  std::fill(constrained_dof.begin(), constrained_dof.end(), 0);
  for (int i = 0; i < n; ++i)
    if (owner[i] >= 0) constrained_dof[3 * i] = constrained_dof[3 * i + 1] = constrained_dof[3 * i + 2] = 1;
  zero_blocks.clear();
  for (int j = 0; j < n; ++j)
    for (int p = blk_outer[j] + 1; p < blk_outer[j + 1]; ++p)
      if (owner[j] >= 0 || owner[blk_row[p]] >= 0) zero_blocks.push_back(p);
  constraints_dirty = false;
}

void Simulator::Impl::check_element_bary(int element, const Eigen::Vector4d& bary) const {
  if (element < 0 || element >= static_cast<int>(elems.size()))
    throw Error("element " + std::to_string(element) + " outside [0, " +
                std::to_string(elems.size()) + ")");
  if (!bary.allFinite() || std::abs(bary.sum() - 1.0) > 1e-9)
    throw Error("barycentric coordinates in element " + std::to_string(element) +
                " must be finite and sum to 1");
}

void Simulator::Impl::check_nodes(const std::vector<int>& nodes) const {
  if (nodes.empty()) throw Error("empty node set");
  std::vector<char> seen(n, 0);
  for (int i : nodes) {
    if (i < 0 || i >= n)
      throw Error("node " + std::to_string(i) + " outside [0, " + std::to_string(n) + ")");
    if (owner[i] >= 0)
      throw Error("node " + std::to_string(i) + " already belongs to handle " +
                  std::to_string(owner[i]));
    if (seen[i]) throw Error("node " + std::to_string(i) + " listed twice");
    seen[i] = 1;
  }
}

int Simulator::Impl::block_index(int i, int j) const {
  if (i < j) std::swap(i, j);
  if (i == j) return blk_outer[j];
  const auto first = blk_row.begin() + blk_outer[j] + 1, last = blk_row.begin() + blk_outer[j + 1];
  const auto it = std::lower_bound(first, last, i);
  return (it != last && *it == i) ? static_cast<int>(it - blk_row.begin()) : -1;
}

double Simulator::Impl::elastic_energy_at(const Eigen::VectorXd& xe, const std::vector<Eigen::Matrix3d>* near) const {
  // each element's energy on the loop, summed here in element order
  std::vector<double> Ee(elems.size());
  detail::for_blocks(parallel, static_cast<long long>(elems.size()), kElementBlock, [&](long long b, long long e) {
    for (long long k = b; k < e; ++k) {
      const Elem& el = elems[static_cast<size_t>(k)];
      const Eigen::Matrix3d F = deformation_gradient(el, xe);
      Eigen::Matrix3d R;
      if (near) R = (*near)[static_cast<size_t>(k)];
      if (!near || !refine_rotation(F, R)) R = rotation(F);
      Ee[static_cast<size_t>(k)] = el.volume * corotational_psi(F, R, el.lame);
    }
  });
  double E = 0.0;
  for (double v : Ee) E += v;
  return E;
}

double Simulator::Impl::poke_energy(const Eigen::VectorXd& xe) const {
  double E = 0.0;
  for (const auto& [id, pk] : pokes)
    E += 0.5 * pk.stiffness * (pk.target - material_point(xe, pk.element, pk.bary)).squaredNorm();
  return E;
}

double Simulator::Impl::incremental(const Eigen::VectorXd& vk, double h, Eigen::VectorXd& xs) const {
  const double own = incremental_own(vk, h, xs);
  return own + potential->energy(xs);
}

double Simulator::Impl::incremental_own(const Eigen::VectorXd& vk, double h, Eigen::VectorXd& xs) const {
  xs = x + h * vk;
  const Eigen::VectorXd dv = vk - v;
  // Its gradient in vk is M (vk - v) - h (f_el + f_ext + f_poke - a M vk - dE/dx) = -r.
  double phi = 0.5 * dv.dot(mass_dof.cwiseProduct(dv)) +
               0.5 * h * params.mass_damping * vk.dot(mass_dof.cwiseProduct(vk)) - h * f_ext.dot(vk);
  // the line's points are near the last assembly's: its rotations are a warm start
  return phi + elastic_energy_at(xs, have_rot ? &rot : nullptr) + poke_energy(xs);
}

std::string Simulator::Impl::add_potential_hessian(const Eigen::VectorXd& xe, double c) {
  pot_blocks.clear();
  potential->hessian_blocks(xe, pot_blocks);
  for (const NodeBlock& b : pot_blocks) {
    const int q = (b.row >= 0 && b.row < n && b.col >= 0 && b.col < n) ? block_index(b.row, b.col) : -1;
    if (q < 0)
      return "potential Hessian block (" + std::to_string(b.row) + ", " + std::to_string(b.col) +
             ") is outside the element pattern";
    if (!b.value.allFinite()) return "potential Hessian block is not finite";
    if (b.row == b.col) blk_val[q] += (0.5 * c) * (b.value + b.value.transpose());
    else if (b.row > b.col) blk_val[q] += c * b.value;  // stored: rows of the larger node
    else blk_val[q] += c * b.value.transpose();
  }
  for (int p : zero_blocks) blk_val[p].setZero();
  rows_stale = inverse_stale = true;
  return {};
}

double Simulator::Impl::admissible(const Eigen::VectorXd& vk, const Eigen::VectorXd& dv, double h) {
  x_trial = x + h * vk;
  const double s = potential->max_step(x_trial, h * dv);
  return s > 0 ? std::min(s, 1.0) : 0.0;  // NaN too: no admissible step
}

bool Simulator::Impl::exact_product(const Eigen::VectorXd& xe, double c, const Eigen::VectorXd& v,
                                    Eigen::VectorXd& out) {
  cg_hv.setZero(3 * n);
  if (!potential->add_hessian_product(xe, v, cg_hv)) return false;
  for (const NodeBlock& b : pot_blocks) {  // A holds c S (add_potential_hessian): take it out
    if (b.row == b.col) {
      cg_hv.segment<3>(3 * b.row) -= 0.5 * (b.value + b.value.transpose()) * v.segment<3>(3 * b.row);
    } else {
      cg_hv.segment<3>(3 * b.row) -= b.value * v.segment<3>(3 * b.col);
      cg_hv.segment<3>(3 * b.col) -= b.value.transpose() * v.segment<3>(3 * b.row);
    }
  }
  product(v, out, false);
  out += c * cg_hv;
  for (int d = 0; d < 3 * n; ++d)
    if (constrained_dof[d]) out(d) = 0.0;
  return true;
}

bool Simulator::Impl::solve_again(const Eigen::VectorXd& b, Eigen::VectorXd& out, std::string& why,
                                  int& iterations) {
  if (used_solver == LinearSolver::LDLT) {
    out = ldlt.solve(b);
  } else {
    Eigen::VectorXd keep = b;
    r.swap(keep);
    const bool ok = solve(why, iterations);  // newton_index = -1: PCG from 0
    r.swap(keep);
    if (!ok) return false;
    out = delta;
  }
  for (int d = 0; d < 3 * n; ++d)
    if (constrained_dof[d]) out(d) = 0.0;
  return out.allFinite();
}

bool Simulator::Impl::exact_step(const Eigen::VectorXd& xe, double c, std::string& why, int& iterations) {
  // Inexact Newton to |residual| <= 1e-2 |r|, at most 30 products: on surface contact 4 to 5
  // products a step, and as few Newton iterations as with a tighter residual.
  constexpr double kRelative = 1e-2;
  constexpr int kProducts = 30;
  cg_z = delta;
  gives_product = exact_product(xe, c, cg_z, cg_q);
  if (!gives_product) return true;
  cg_p = cg_z;
  cg_res = r;
  cg_d.setZero(3 * n);
  double rz = cg_res.dot(cg_z);
  const double goal = kRelative * r.norm();
  for (int k = 1;; ++k) {
    const double pq = cg_p.dot(cg_q);
    if (!(pq > 0)) break;  // not positive along p (round-off): the step so far
    const double alpha = rz / pq;
    cg_d += alpha * cg_p;
    cg_res -= alpha * cg_q;
    if (k >= kProducts || cg_res.norm() <= goal) break;
    cg_z_old.swap(cg_z);
    inner_tolerance = inner_relative();
    const bool solved = solve_again(cg_res, cg_z, why, iterations);
    inner_tolerance = 0.0;
    if (!solved) return false;
    // flexible (Polak-Ribiere) beta: the inexact inner solves are not one fixed preconditioner
    const double rz_next = cg_res.dot(cg_z);
    cg_p = cg_z + ((rz_next - cg_res.dot(cg_z_old)) / rz) * cg_p;
    rz = rz_next;
    exact_product(xe, c, cg_p, cg_q);
  }
  if (cg_d.squaredNorm() > 0) delta = cg_d;
  return true;
}

bool Simulator::Impl::line_search(Eigen::VectorXd& vk, double h, double& phi) {
  const double slope = -r.dot(delta);  // d phi / ds at s = 0 (r = -grad phi on free dofs)
  if (!(slope < 0)) return false;
  double step = admissible(vk, delta, h);  // x_trial = x + h vk
  if (step == 0.0) return false;
  potential->begin_line(x_trial, h * delta);  // the potential at x + h (vk + s delta)
  for (int k = 0; k < 40; ++k, step *= 0.5) {
    trial = vk + step * delta;
    const double value = incremental_own(trial, h, x_trial) + potential->energy_along(step);
    if (std::isfinite(value) && value <= phi + 1e-4 * step * slope) {
      potential->end_line(step);
      vk.swap(trial);
      phi = value;
      delta *= step;
      return true;
    }
    ++halvings;
  }
  return false;
}

double Simulator::Impl::assemble_elastic(const Eigen::VectorXd& xe, double cK,
                                         const Eigen::VectorXd* vd, bool warm,
                                         std::vector<Eigen::Matrix3d>& rots,
                                         std::vector<Eigen::Matrix3d>& blocks, Eigen::VectorXd& f,
                                         Eigen::VectorXd& Kvd, ElementTerms& et) const {
  // Elements on the loop, then each node gathers its elements' parts in element order: the same
  // sums as one pass over the elements, and no two threads write one block or force.
  et.resize(elems.size(), vd != nullptr);
  if (!parallel) {  // one pass, each element's parts added while in cache
    f.setZero(3 * n);
    if (vd) Kvd.setZero(3 * n);
    double energy = 0.0;
    for (size_t e = 0; e < elems.size(); ++e) {
      element_terms(e, xe, vd, warm, rots[e], et);
      add_element(e, cK, et, blocks, f, vd ? &Kvd : nullptr);
      energy += et.energy[e];
    }
    return energy;
  }
  detail::for_blocks(parallel, static_cast<long long>(elems.size()), kElementBlock, [&](long long b, long long e) {
    for (long long k = b; k < e; ++k) element_terms(static_cast<size_t>(k), xe, vd, warm, rots[static_cast<size_t>(k)], et);
  });
  f.resize(3 * n);
  if (vd) Kvd.resize(3 * n);
  detail::for_blocks(parallel, n, detail::BlockRows::kNodes, [&](long long b, long long e) {
    for (long long j = b; j < e; ++j) node_terms(static_cast<int>(j), cK, et, blocks, f, vd ? &Kvd : nullptr);
  });
  double energy = 0.0;
  for (double E : et.energy) energy += E;
  return energy;
}

void Simulator::Impl::element_terms(size_t e, const Eigen::VectorXd& xe, const Eigen::VectorXd* vd,
                                    bool warm, Eigen::Matrix3d& R, ElementTerms& et) const {
  const Elem& el = elems[e];
  const Eigen::Matrix3d F = deformation_gradient(el, xe);
  if (!warm || !refine_rotation(F, R)) R = rotation(F);
  et.energy[e] = el.volume * corotational_psi(F, R, el.lame);
  et.force[e] = tet_forces(el.grad, el.volume, corotational_stress(F, R, el.lame));
  if (vd) {
    Eigen::Matrix<double, 3, 4> vc;
    for (int a = 0; a < 4; ++a) vc.col(a) = vd->segment<3>(3 * el.node[a]);
    et.Kv[e] = warped_tet_product(el.grad, el.volume, el.lame, R, vc);
  }
  et.RG[e].noalias() = R * el.grad;
}

void Simulator::Impl::add_element(size_t e, double cK, const ElementTerms& et,
                                  std::vector<Eigen::Matrix3d>& blocks, Eigen::VectorXd& f,
                                  Eigen::VectorXd* Kvd) const {
  const Elem& el = elems[e];
  for (int c = 0; c < 4; ++c) {
    f.segment<3>(3 * el.node[c]) += et.force[e].col(c);
    if (Kvd) Kvd->segment<3>(3 * el.node[c]) += et.Kv[e].col(c);
    for (int a = 0; a < 4; ++a)
      if (const int q = el.blk[a][c]; q >= 0) blocks[q] += stiffness_block(el, et.RG[e], cK, a, c);
  }
}

void Simulator::Impl::node_terms(int j, double cK, const ElementTerms& et,
                                 std::vector<Eigen::Matrix3d>& blocks, Eigen::VectorXd& f,
                                 Eigen::VectorXd* Kvd) const {
  Eigen::Vector3d fj = Eigen::Vector3d::Zero(), kj = Eigen::Vector3d::Zero();
  for (int k = incidence_start[j]; k < incidence_start[j + 1]; ++k) {
    const size_t e = static_cast<size_t>(incidence[k] / 4);
    const int c = incidence[k] % 4;
    const Elem& el = elems[e];
    fj += et.force[e].col(c);
    if (Kvd) kj += et.Kv[e].col(c);
    // column j's blocks of this element: rows of its nodes >= j
    for (int a = 0; a < 4; ++a)
      if (const int q = el.blk[a][c]; q >= 0) blocks[q] += stiffness_block(el, et.RG[e], cK, a, c);
  }
  f.segment<3>(3 * j) = fj;
  if (Kvd) Kvd->segment<3>(3 * j) = kj;
}

double Simulator::Impl::assemble(const Eigen::VectorXd& xe, double cM, double cK, double cP,
                                 const Eigen::VectorXd* vd) {
  if (constraints_dirty) update_constraints();
  std::fill(blk_val.begin(), blk_val.end(), Eigen::Matrix3d::Zero());
  const double energy = assemble_elastic(xe, cK, vd, have_rot, rot, blk_val, f_el, Kv, terms);
  // Pokes: k b_a b_b I on the element's blocks.
  for (const auto& [id, pk] : pokes) {
    const Elem& el = elems[pk.element];
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const int q = el.blk[a][b];
        if (q >= 0) blk_val[q].diagonal().array() += cP * pk.stiffness * pk.bary(a) * pk.bary(b);
      }
  }
  for (int i = 0; i < n; ++i) blk_val[blk_outer[i]].diagonal().array() += cM * mass(i);
  for (int p : zero_blocks) blk_val[p].setZero();
  have_rot = true;
  rows_stale = inverse_stale = true;
  return energy;
}

void Simulator::Impl::external_forces() {
  f_ext.resize(3 * n);
  for (int i = 0; i < n; ++i) f_ext.segment<3>(3 * i) = mass(i) * params.gravity;
  for (const auto& [id, pf] : forces)
    for (int a = 0; a < 4; ++a) f_ext.segment<3>(3 * elems[pf.element].node[a]) += pf.bary(a) * pf.force;
}

void Simulator::Impl::add_poke_forces(const Eigen::VectorXd& xe, Eigen::VectorXd& f) const {
  for (const auto& [id, pk] : pokes) {
    const Eigen::Vector3d pull = pk.stiffness * (pk.target - material_point(xe, pk.element, pk.bary));
    for (int a = 0; a < 4; ++a) f.segment<3>(3 * elems[pk.element].node[a]) += pk.bary(a) * pull;
  }
}

bool Simulator::Impl::solve(std::string& why, int& iterations) {
  if (used_solver == LinearSolver::LDLT) {
    double* val = A.valuePtr();
    const double* src = blk_val.front().data();
    for (size_t p = 0; p < csc_from_blk.size(); ++p) val[p] = src[csc_from_blk[p]];
    ldlt.factorize(A);
    if (ldlt.info() != Eigen::Success) {
      why = "sparse LDLT factorisation failed (matrix not positive definite)";
      return false;
    }
    delta = ldlt.solve(r);
    const double dmin = ldlt.vectorD().minCoeff();
    if (!(dmin > 0)) {
      why = "system matrix not positive definite (LDLT pivot " + std::to_string(dmin) + ")";
      return false;
    }
  } else if (!pcg_solve(why, iterations)) {
    if (params.solver != LinearSolver::Auto) return false;
    auto_fell_back = true;  // e.g. a very stiff or tiny mesh: fall back to the direct solver
    resolve_solver();
    return solve(why, iterations);
  }
  if (!delta.allFinite()) {
    why = "linear solve produced non-finite values";
    return false;
  }
  return true;
}

bool Simulator::Impl::invert_diagonal(std::string& why) {
  if (!inverse_stale) return true;
  block_inv.resize(n);
  std::vector<char> singular(n, 0);
  detail::for_blocks(parallel, n, detail::BlockRows::kNodes, [&](long long b, long long e) {
    for (long long i = b; i < e; ++i) {
      bool invertible = false;
      blk_val[blk_outer[i]].computeInverseWithCheck(block_inv[i], invertible);
      singular[i] = !invertible || !block_inv[i].allFinite();
    }
  });
  const auto bad = std::find(singular.begin(), singular.end(), 1);
  if (bad != singular.end()) {
    why = "singular diagonal block at node " + std::to_string(bad - singular.begin());
    return false;
  }
  inverse_stale = false;
  return true;
}

double Simulator::Impl::product(const Eigen::VectorXd& v, Eigen::VectorXd& out, bool dot) {
  if (rows_stale) rows.gather(blk_val, parallel);
  rows_stale = false;
  return rows.multiply(v, out, dot, parallel);
}

std::array<double, 2> Simulator::Impl::pcg_update(double alpha, long long b, long long e) {
  double rr = 0.0, rz = 0.0;
  for (long long i = b; i < e; ++i) {
    if (alpha != 0.0) {  // 0: the first pass, before any direction
      delta.segment<3>(3 * i) += alpha * pcg_p.segment<3>(3 * i);
      pcg_r.segment<3>(3 * i) -= alpha * pcg_q.segment<3>(3 * i);
    }
    const Eigen::Vector3d ri = pcg_r.segment<3>(3 * i);
    const Eigen::Vector3d zi = block_inv[i] * ri;
    pcg_z.segment<3>(3 * i) = zi;
    rr += ri.dot(ri);
    rz += ri.dot(zi);
  }
  return {rr, rz};
}

bool Simulator::Impl::pcg_solve(std::string& why, int& iterations) {
  // Block-Jacobi (3x3 per node) preconditioned CG, warm-started from the previous solution.
  // Its node loops run in fixed blocks, its sums per block in block order (block_rows.hpp).
  const int N = 3 * n;
  if (!invert_diagonal(why)) return false;
  bool warm = false;
  if (newton_index == 0 && guess1.size() == N) {
    // Linear extrapolation of the last two first-iteration solutions (measured: 8-15% fewer
    // iterations than reusing the last one).
    if (guess2.size() == N) delta = 2.0 * guess1 - guess2;
    else delta = guess1;
    warm = true;
  } else {
    delta.setZero(N);
  }
  for (int d = 0; d < N; ++d)
    if (constrained_dof[d]) delta(d) = 0.0;
  const double bnorm = r.norm();
  if (bnorm == 0.0) {
    delta.setZero();
    return true;
  }
  if (warm) {
    product(delta, pcg_q, false);
    pcg_r = r - pcg_q;
  } else {
    pcg_r = r;  // A 0 = 0
  }
  const double goal = (inner_tolerance > 0 ? inner_tolerance : params.pcg_tolerance) * bnorm;
  pcg_z.resize(N);
  using Sums = std::array<double, 2>;
  Sums s = detail::sum_blocks<2>(parallel, n, detail::BlockRows::kNodes,
                                 [&](long long b, long long e) { return pcg_update(0.0, b, e); });
  pcg_p = pcg_z;
  double rz = s[1];
  int it = 0;
  double rnorm = std::sqrt(s[0]);
  while (rnorm > goal && it < params.pcg_max_iterations) {
    const double pq = product(pcg_p, pcg_q, true);
    if (!(pq > 0)) {
      why = "PCG met a non-positive curvature (matrix not positive definite)";
      return false;
    }
    const double alpha = rz / pq;
    s = detail::sum_blocks<2>(parallel, n, detail::BlockRows::kNodes,
                              [&](long long b, long long e) { return pcg_update(alpha, b, e); });
    rnorm = std::sqrt(s[0]);
    ++it;
    if (rnorm <= goal) break;
    const double beta = s[1] / rz;
    rz = s[1];
    detail::for_blocks(parallel, n, detail::BlockRows::kNodes, [&](long long b, long long e) {
      pcg_p.segment(3 * b, 3 * (e - b)) = pcg_z.segment(3 * b, 3 * (e - b)) + beta * pcg_p.segment(3 * b, 3 * (e - b));
    });
  }
  iterations += it;
  if (!(rnorm <= goal)) {
    why = "PCG did not converge in " + std::to_string(it) + " iterations (relative residual " +
          std::to_string(rnorm / bnorm) + ")";
    return false;
  }
  return true;
}

void Simulator::Impl::prescribed(double time, Eigen::VectorXd& pos) const {
  for (const auto& [id, k] : kinematic)
    for (size_t j = 0; j < k.nodes.size(); ++j)
      pos.segment<3>(3 * k.nodes[j]) = k.position(static_cast<int>(j), time);
}

std::string Simulator::Impl::substep(double h, int& newton, int& iters, double& t_asm,
                                     double& t_solve) {
  const bool be = params.integrator == Integrator::BackwardEuler;
  // x_eval = x + h (th1 v + th2 v+), damping velocity ph1 v + ph2 v+, x+ = x + h (ps1 v + ps2 v+)
  const double th1 = be ? 0.0 : 0.25, th2 = be ? 1.0 : 0.25;
  const double ph1 = be ? 0.0 : 0.5, ph2 = be ? 1.0 : 0.5;
  const double ps1 = be ? 0.0 : 0.5, ps2 = be ? 1.0 : 0.5;
  const double a = params.mass_damping, b = params.stiffness_damping;
  external_forces();
  if (potential) potential->begin_substep_at(t, t + h, x, v);
  Eigen::VectorXd vk = v;
  Eigen::VectorXd target = x;
  prescribed(t + h, target);
  if (constraints_dirty) update_constraints();
  for (int d = 0; d < 3 * n; ++d)
    if (constrained_dof[d]) vk(d) = ((target(d) - x(d)) / h - ps1 * v(d)) / ps2;
  if (potential) {
    // First guess: the old velocity plus the last substep's change of it (a smooth motion's
    // next velocity to first order); the old velocity when the potential does not admit that
    // move from the start positions, rest when it does not admit either.
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(3 * n);
    const bool extrapolate = last_h > 0 && last_v.size() == v.size();
    if (extrapolate)
      for (int d = 0; d < 3 * n; ++d)
        if (!constrained_dof[d]) vk(d) = v(d) + (h / last_h) * (v(d) - last_v(d));
    if (extrapolate && admissible(zero, vk, h) < 1.0)
      for (int d = 0; d < 3 * n; ++d)
        if (!constrained_dof[d]) vk(d) = v(d);
    if (admissible(zero, vk, h) < 1.0)
      for (int d = 0; d < 3 * n; ++d)
        if (!constrained_dof[d]) vk(d) = 0.0;
  }
  Eigen::VectorXd xe(3 * n), vd(3 * n);
  for (int it = 0; it < params.newton_iterations; ++it) {
    auto t0 = Clock::now();
    xe = x + h * (th1 * v + th2 * vk);
    const bool damp_k = b > 0;
    if (damp_k || a > 0) vd = ph1 * v + ph2 * vk;
    last_elastic = assemble(xe, 1.0 + h * ph2 * a, h * h * th2 + h * ph2 * b, h * h * th2,
                            damp_k ? &vd : nullptr);
    // r = -(M (vk - v) - h (f_el + f_ext + f_poke - a M vd - b K vd - dE/dx))
    Eigen::VectorXd f = f_el + f_ext;
    if (potential) {
      if (std::string why = add_potential_hessian(xe, h * h * th2); !why.empty()) return why;
      pot_grad.setZero(3 * n);
      potential->add_gradient(xe, pot_grad);
      if (!pot_grad.allFinite()) return "potential gradient is not finite";
      f -= pot_grad;
    }
    add_poke_forces(xe, f);
    if (a > 0) f -= a * mass_dof.cwiseProduct(vd);
    if (damp_k) f -= b * Kv;
    r = h * f - mass_dof.cwiseProduct(vk - v);
    for (int d = 0; d < 3 * n; ++d)
      if (constrained_dof[d]) r(d) = 0.0;
    t_asm += ms_since(t0);
    t0 = Clock::now();
    std::string why;
    newton_index = it;
    // exact_step's first preconditioner solve, to its inner tolerance, when it is to follow
    if (potential && gives_product) inner_tolerance = inner_relative();
    bool ok = solve(why, iters);
    newton_index = -1;
    inner_tolerance = 0.0;
    if (ok && it == 0) {
      guess2.swap(guess1);
      guess1 = delta;
    }
    if (ok && potential) ok = exact_step(xe, h * h * th2, why, iters);
    t_solve += ms_since(t0);
    ++newton;
    if (!ok) return why;
    double dmax = 0.0;  // of the full Newton update: a shortened step is not convergence
    for (int i = 0; i < n; ++i) dmax = std::max(dmax, delta.segment<3>(3 * i).norm());
    if (!potential) {
      vk += delta;
    } else {
      if (it == 0) {
        phi_history.assign(1, incremental(vk, h, x_trial));
        if (!std::isfinite(phi_history[0])) return "incremental potential is not finite";
      }
      double phi = phi_history.back();
      if (!line_search(vk, h, phi)) break;  // no descent left: converged to round-off
      phi_history.push_back(phi);
    }
    if (params.newton_tolerance > 0 && dmax <= params.newton_tolerance) break;
  }
  const Eigen::VectorXd x_old = x;
  x += h * (ps1 * v + ps2 * vk);
  last_v = v;
  last_h = h;
  v = vk;
  for (int d = 0; d < 3 * n; ++d)
    if (constrained_dof[d]) {
      x(d) = target(d);
      v(d) = (target(d) - x_old(d)) / h;
    }
  if (params.ground) ground();
  if (!x.allFinite() || !v.allFinite()) return "non-finite positions or velocities";
  const double kinetic = 0.5 * v.dot(mass_dof.cwiseProduct(v));
  double limit = params.max_energy;
  if (limit == 0.0) {  // automatic: material scale plus what the pokes can put in
    limit = energy_limit;
    for (const auto& [id, pk] : pokes)
      limit += 10.0 * pk.stiffness * (pk.target - material_point(x_old, pk.element, pk.bary)).squaredNorm();
  }
  if (!(kinetic + last_elastic <= limit)) {
    char msg[128];
    std::snprintf(msg, sizeof msg, "runaway energy %.3g J (limit %.3g J)", kinetic + last_elastic, limit);
    return msg;
  }
  return {};
}

void Simulator::Impl::ground() {
  const Eigen::Vector3d nrm = params.ground_plane.normal.normalized();
  const double off = params.ground_plane.offset / params.ground_plane.normal.norm();
  for (int i = 0; i < n; ++i) {
    if (owner[i] >= 0) continue;
    const double dist = nrm.dot(x.segment<3>(3 * i)) - off;
    if (dist >= 0) continue;
    x.segment<3>(3 * i) -= dist * nrm;
    Eigen::Vector3d vi = v.segment<3>(3 * i);
    const double vn = nrm.dot(vi);
    Eigen::Vector3d vt = vi - vn * nrm;
    vi = (1.0 - params.ground_plane.friction) * vt + std::max(vn, 0.0) * nrm;
    v.segment<3>(3 * i) = vi;
  }
}

// ------------------------------------------------------------------ public

Simulator::Simulator(const Eigen::Ref<const Eigen::MatrixXd>& U,
                     const Eigen::Ref<const Eigen::MatrixXi>& T, const Material& material,
                     const Parameters& params, const std::vector<Material>& per_element)
    : impl_(std::make_unique<Impl>()) {
  check_params(params);
  impl_->params = params;
  impl_->build(U, T, material, per_element);
}
Simulator::~Simulator() = default;
Simulator::Simulator(Simulator&&) noexcept = default;
Simulator& Simulator::operator=(Simulator&&) noexcept = default;

int Simulator::fix(const std::vector<int>& nodes) { return add_kinematic(nodes, RigidMotion{}); }

int Simulator::add_kinematic(const std::vector<int>& nodes, const RigidMotion& motion) {
  Impl& s = *impl_;
  s.check_nodes(nodes);
  if (!motion.center.allFinite() || !motion.axis.allFinite() ||
      !std::isfinite(motion.angular_velocity) || !motion.velocity.allFinite() ||
      std::isnan(motion.start) || std::isnan(motion.stop))
    throw Error("rigid motion has a non-finite field");
  if (motion.angular_velocity != 0.0 && motion.axis.norm() == 0.0)
    throw Error("rotation axis is zero");
  if (motion.stop < motion.start)
    throw Error("stop time is before start time");
  Kinematic k;
  k.nodes = nodes;
  k.motion = motion;
  k.p0.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (size_t j = 0; j < nodes.size(); ++j) k.p0.row(j) = s.node(s.x, nodes[j]).transpose();
  const int id = s.next_id++;
  for (int i : nodes) s.owner[i] = id;
  s.kinematic.emplace(id, std::move(k));
  s.constraints_dirty = true;
  return id;
}

int Simulator::add_point_force(int element, const Eigen::Vector4d& bary,
                               const Eigen::Vector3d& force) {
  impl_->check_element_bary(element, bary);
  if (!force.allFinite())
    throw Error("force " + vec_str(force) + " is not finite");
  const int id = impl_->next_id++;
  impl_->forces.emplace(id, PointForce{element, bary, force});
  return id;
}

void Simulator::set_point_force(int handle, const Eigen::Vector3d& force) {
  auto it = impl_->forces.find(handle);
  if (it == impl_->forces.end())
    throw Error("handle " + std::to_string(handle) +
                " is not a point force");
  if (!force.allFinite())
    throw Error("force " + vec_str(force) + " for handle " +
                std::to_string(handle) + " is not finite");
  it->second.force = force;
}

int Simulator::add_poke(int element, const Eigen::Vector4d& bary, const Eigen::Vector3d& target,
                        double stiffness) {
  impl_->check_element_bary(element, bary);
  if (!target.allFinite()) throw Error("target " + vec_str(target) + " is not finite");
  if (!std::isfinite(stiffness) || stiffness <= 0)
    throw Error("stiffness must be finite and > 0 N/m, got " +
                std::to_string(stiffness));
  const int id = impl_->next_id++;
  impl_->pokes.emplace(id, Poke{element, bary, target, stiffness});
  return id;
}

void Simulator::set_poke_target(int handle, const Eigen::Vector3d& target) {
  auto it = impl_->pokes.find(handle);
  if (it == impl_->pokes.end())
    throw Error("handle " + std::to_string(handle) + " is not a poke");
  if (!target.allFinite())
    throw Error("target " + vec_str(target) + " for handle " +
                std::to_string(handle) + " is not finite");
  it->second.target = target;
}

void Simulator::remove(int handle) {
  Impl& s = *impl_;
  if (auto it = s.kinematic.find(handle); it != s.kinematic.end()) {
    for (int i : it->second.nodes) s.owner[i] = -1;
    s.kinematic.erase(it);
    s.constraints_dirty = true;
  } else if (!s.forces.erase(handle) && !s.pokes.erase(handle)) {
    throw Error("no handle " + std::to_string(handle));
  }
}

bool Simulator::has_handle(int handle) const {
  return impl_->kinematic.count(handle) || impl_->forces.count(handle) ||
         impl_->pokes.count(handle);
}

StepResult Simulator::step() {
  Impl& s = *impl_;
  const auto t0 = Clock::now();
  StepResult res;
  res.step = s.steps + 1;
  const Eigen::VectorXd x0 = s.x, v0 = s.v;
  const double time0 = s.t;
  const double h = s.params.dt / s.params.substeps;
  std::string why;
  s.halvings = 0;
  s.phi_history.clear();
  for (int k = 0; k < s.params.substeps && why.empty(); ++k) {
    why = s.substep(h, res.newton_iterations, res.solver_iterations, res.assemble_ms, res.solve_ms);
    if (why.empty()) s.t = time0 + (k + 1) * h;
  }
  res.line_search_halvings = s.halvings;
  res.incremental_potential = s.phi_history;
  if (!why.empty()) {
    s.x = x0;
    s.v = v0;
    s.t = time0;
    res.success = false;
    res.message = "step " + std::to_string(res.step) + " (t = " +
                  std::to_string(time0) + " s) failed: " + why +
                  "; state left at the last good step";
  } else {
    s.t = time0 + s.params.dt;
    ++s.steps;
  }
  res.time = s.t;
  s.sync_out();
  res.total_ms = ms_since(t0);
  return res;
}

StaticResult Simulator::solve_static(int max_iterations, double tolerance) {
  Impl& s = *impl_;
  StaticResult res;
  if (max_iterations < 1) throw Error("max_iterations must be >= 1");
  if (!std::isfinite(tolerance) || tolerance < 0)
    throw Error("tolerance must be finite and >= 0 N");
  const Eigen::VectorXd x0 = s.x, v0 = s.v;
  s.prescribed(s.t, s.x);
  s.external_forces();
  double tol = tolerance;
  auto max_node = [&](const Eigen::VectorXd& f) {
    double m = 0.0;
    for (int i = 0; i < s.n; ++i)
      if (s.owner[i] < 0) m = std::max(m, f.segment<3>(3 * i).norm());
    return m;
  };
  const LinearSolver keep = s.used_solver;
  for (int it = 0; it < max_iterations; ++it) {
    s.assemble(s.x, 0.0, 1.0, 1.0, nullptr);
    Eigen::VectorXd f = s.f_el + s.f_ext;
    s.add_poke_forces(s.x, f);
    for (int d = 0; d < 3 * s.n; ++d)
      if (s.constrained_dof[d]) f(d) = 0.0;
    res.residual = max_node(f);
    if (it == 0 && tol == 0.0) {
      Eigen::VectorXd fe = s.f_el;
      for (int d = 0; d < 3 * s.n; ++d)
        if (s.constrained_dof[d]) fe(d) = 0.0;
      tol = 1e-10 * (max_node(s.f_ext) + max_node(fe) + max_node(f));
    }
    res.iterations = it;
    if (res.residual <= tol) {
      res.converged = true;
      break;
    }
    s.r = f;
    std::string why;
    int dummy = 0;
    if (s.used_solver != LinearSolver::LDLT) {  // static systems are better solved directly
      s.used_solver = LinearSolver::LDLT;
      if (!s.ldlt_analysed) {
        s.ldlt.analyzePattern(s.A);
        s.ldlt_analysed = true;
      }
    }
    if (!s.solve(why, dummy)) {
      res.message = "static solve iteration " + std::to_string(it) + ": " + why;
      break;
    }
    s.x += s.delta;
    res.iterations = it + 1;
    // Automatic tolerance: also stop once the update is at round-off level (the force
    // residual's own round-off floor, ~1e-16 E h^2 |x| / h, can exceed 1e-10 |f_ext|).
    if (tolerance == 0.0) {
      double dmax = 0.0;
      for (int i = 0; i < s.n; ++i) dmax = std::max(dmax, s.delta.segment<3>(3 * i).norm());
      if (dmax <= 1e-13 * s.bbox_diagonal) {
        res.converged = true;
        break;
      }
    }
  }
  s.used_solver = keep;
  if (res.converged && !s.x.allFinite()) res.converged = false;
  if (!res.converged) {
    if (res.message.empty())
      res.message = "no convergence in " + std::to_string(max_iterations) +
                    " iterations (residual " + std::to_string(res.residual) + " N, tolerance " +
                    std::to_string(tol) + " N)";
    s.x = x0;
    s.v = v0;
  } else {
    s.v.setZero();
  }
  s.sync_out();
  return res;
}

Eigen::SparseMatrix<double> Simulator::stiffness() const {
  const Impl& s = *impl_;
  std::vector<Eigen::Matrix3d> rots = s.rot;
  std::vector<Eigen::Matrix3d> blocks(s.blk_val.size(), Eigen::Matrix3d::Zero());
  Eigen::VectorXd f, unused;
  ElementTerms et;
  s.assemble_elastic(s.x, 1.0, nullptr, s.have_rot, rots, blocks, f, unused, et);
  // Lower node blocks (rows i >= column j) to both triangles.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(18 * blocks.size());
  for (int j = 0; j < s.n; ++j)
    for (int p = s.blk_outer[j]; p < s.blk_outer[j + 1]; ++p) {
      const int i = s.blk_row[p];
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
          trip.emplace_back(3 * i + k, 3 * j + l, blocks[p](k, l));
          if (i != j) trip.emplace_back(3 * j + l, 3 * i + k, blocks[p](k, l));
        }
    }
  Eigen::SparseMatrix<double> K(3 * s.n, 3 * s.n);
  K.setFromTriplets(trip.begin(), trip.end());
  return K;
}

Eigen::MatrixXd Simulator::elastic_forces() const {
  const Impl& s = *impl_;
  std::vector<Eigen::Matrix3d> rots = s.rot;
  std::vector<Eigen::Matrix3d> blocks(s.blk_val.size(), Eigen::Matrix3d::Zero());
  Eigen::VectorXd f, unused;
  ElementTerms et;
  s.assemble_elastic(s.x, 0.0, nullptr, s.have_rot, rots, blocks, f, unused, et);
  using RowMajorN3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  return Eigen::Map<const RowMajorN3>(f.data(), s.n, 3);
}

const Eigen::MatrixXd& Simulator::positions() const { return impl_->Xout; }
const Eigen::MatrixXd& Simulator::velocities() const { return impl_->Vout; }

void Simulator::set_positions(const Eigen::Ref<const Eigen::MatrixXd>& X) {
  Impl& s = *impl_;
  if (X.rows() != s.n || X.cols() != 3)
    throw Error("positions must be " + std::to_string(s.n) + " x 3");
  for (int i = 0; i < s.n; ++i) {
    if (!X.row(i).allFinite())
      throw Error("position of node " + std::to_string(i) + " is not finite");
    s.x.segment<3>(3 * i) = X.row(i).transpose();
  }
  s.last_h = 0.0;  // no last substep to extrapolate from
  s.sync_out();
}

void Simulator::set_velocities(const Eigen::Ref<const Eigen::MatrixXd>& V) {
  Impl& s = *impl_;
  if (V.rows() != s.n || V.cols() != 3)
    throw Error("velocities must be " + std::to_string(s.n) + " x 3");
  for (int i = 0; i < s.n; ++i) {
    if (!V.row(i).allFinite())
      throw Error("velocity of node " + std::to_string(i) + " is not finite");
    s.v.segment<3>(3 * i) = V.row(i).transpose();
  }
  s.last_h = 0.0;  // no last substep to extrapolate from
  s.sync_out();
}

void Simulator::reset() {
  Impl& s = *impl_;
  for (int i = 0; i < s.n; ++i) s.x.segment<3>(3 * i) = s.U.row(i).transpose();
  s.v.setZero();
  s.t = 0.0;
  s.steps = 0;
  s.guess1.resize(0);
  s.guess2.resize(0);
  s.have_rot = false;
  s.last_h = 0.0;  // no last substep to extrapolate from
  s.sync_out();
}

double Simulator::time() const { return impl_->t; }
long Simulator::step_count() const { return impl_->steps; }

double Simulator::kinetic_energy() const {
  return 0.5 * impl_->v.dot(impl_->mass_dof.cwiseProduct(impl_->v));
}

double Simulator::elastic_energy() const { return impl_->elastic_energy_at(impl_->x); }

double Simulator::gravity_energy() const {
  const Impl& s = *impl_;
  double E = 0.0;
  for (int i = 0; i < s.n; ++i) E -= s.mass(i) * s.params.gravity.dot(s.x.segment<3>(3 * i));
  return E;
}

Eigen::Vector3d Simulator::linear_momentum() const {
  const Impl& s = *impl_;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < s.n; ++i) p += s.mass(i) * s.v.segment<3>(3 * i);
  return p;
}

Eigen::Vector3d Simulator::angular_momentum() const {
  const Impl& s = *impl_;
  Eigen::Vector3d L = Eigen::Vector3d::Zero();
  for (int i = 0; i < s.n; ++i)
    L += s.mass(i) * s.x.segment<3>(3 * i).cross(s.v.segment<3>(3 * i));
  return L;
}

double Simulator::rest_volume() const { return impl_->total_volume; }

double Simulator::volume() const {
  const Impl& s = *impl_;
  double V = 0.0;
  for (const Elem& el : s.elems) {
    const Eigen::Matrix3d F = deformation_gradient(el, s.x);
    V += el.volume * F.determinant();
  }
  return V;
}

int Simulator::nodes() const { return impl_->n; }
int Simulator::elements() const { return static_cast<int>(impl_->elems.size()); }
const Eigen::MatrixXd& Simulator::rest_positions() const { return impl_->U; }
const Eigen::MatrixXi& Simulator::tets() const { return impl_->T; }
const Eigen::VectorXd& Simulator::masses() const { return impl_->mass; }
const Parameters& Simulator::params() const { return impl_->params; }

static void check_potential_params(const Parameters& p) {
  if (p.integrator != Integrator::BackwardEuler)
    throw Error("parameter integrator must be BackwardEuler with a potential");
  if (p.stiffness_damping != 0.0)
    throw Error("parameter stiffness_damping must be 0 with a potential");
}

void Simulator::set_potential(std::shared_ptr<Potential> potential) {
  if (potential) check_potential_params(impl_->params);
  impl_->potential = std::move(potential);
  impl_->gives_product = false;
}

const std::shared_ptr<Potential>& Simulator::potential() const { return impl_->potential; }

void Simulator::set_parallel_for(ParallelFor loop) { impl_->parallel = std::move(loop); }

bool Simulator::adjacent(int i, int j) const {
  const Impl& s = *impl_;
  if (i < 0 || i >= s.n || j < 0 || j >= s.n)
    throw Error("node pair (" + std::to_string(i) + ", " + std::to_string(j) + ") outside [0, " +
                std::to_string(s.n) + ")");
  return s.block_index(i, j) >= 0;
}

void Simulator::set_params(const Parameters& params) {
  check_params(params);
  if (impl_->potential) check_potential_params(params);
  impl_->params = params;
  impl_->resolve_solver();
}

LinearSolver Simulator::solver() const { return impl_->used_solver; }

}  // namespace mbi::sim
