#pragma once
// Co-rotational FEM simulator of a tetrahedral control mesh (method.md, "Simulator").
//
//   Simulator sim(U, T, material, params);     // U n x 3 (m), T m x 4
//   sim.fix(nodes);                             // or add_kinematic(nodes, motion)
//   int poke = sim.add_poke(element, bary, target, 1e3);
//   per frame: sim.set_poke_target(poke, p); StepResult r = sim.step(); sim.positions();
//
// Units: SI throughout (m, s, kg, N, Pa, J). Time starts at 0 and advances by params.dt per
// step() (split into params.substeps equal substeps).
//
// Time integration (per substep h = dt / substeps), unknown v+ (3n), D = a M + b K:
//   BackwardEuler:    M (v+ - v) = h f(x + h v+)            - h D v+,  x+ = x + h v+
//   ImplicitMidpoint: M (v+ - v) = h f(x + h (v + v+) / 4)  - h D (v + v+) / 2,
//                     x+ = x + h (v + v+) / 2
// f = elastic + external forces. Each Newton iteration linearises the elastic force with the
// warped stiffness K = sum_e R_e K_e R_e^T at the current guess and makes one sparse linear
// solve; the first iteration starts from x (Mueller-Gross "one solve per step"). The matrix
// sparsity pattern is analysed once; constrained dofs keep their rows (set to identity) so that
// adding or removing handles never re-analyses it.
//
// Backward Euler is the default: unconditionally stable, dissipative (it also loses angular
// momentum of spinning bodies at O(h^2 w^2) per step). Implicit midpoint conserves linear and
// angular momentum (to the Newton tolerance) and does not damp, but is not L-stable: use it
// with newton_iterations > 1 and a tolerance.
#include <mbi/sim/corotational.hpp>
#include <mbi/sim/potential.hpp>

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace mbi::sim {

enum class Integrator { BackwardEuler, ImplicitMidpoint };

/// Linear solver of each Newton iteration (see bench/bench_sim.cpp for the measurements):
///   LDLT: Eigen SimplicialLDLT, AMD ordering, symbolic analysis once, numeric factorisation
///         per solve; exact; fastest below ~1K dofs, slow on large 3D meshes (fill-in).
///   PCG:  conjugate gradients with a 3x3 block-Jacobi preconditioner on the node-block matrix,
///         warm-started from the previous solution; relative residual <= pcg_tolerance.
///   Auto: LDLT below 600 dofs, PCG above; if PCG fails to converge (very ill-conditioned
///         systems) it switches to LDLT for good and redoes the solve.
enum class LinearSolver { Auto, LDLT, PCG };

/// Ground plane: points with dot(normal, x) < offset are projected back onto the plane after
/// each substep; their inward normal velocity is removed and their tangential velocity scaled
/// by (1 - friction).
struct GroundPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  ///< need not be unit length (normalised)
  double offset = 0.0;                                ///< m, plane is dot(n, x) = offset
  double friction = 0.0;                              ///< in [0, 1]
};

struct Parameters {
  double dt = 1.0 / 60.0;                         ///< s per step(), > 0
  int substeps = 1;                               ///< >= 1
  Eigen::Vector3d gravity = Eigen::Vector3d(0, -9.81, 0);  ///< m/s^2
  double mass_damping = 0.0;                      ///< Rayleigh a, 1/s, >= 0
  double stiffness_damping = 0.0;                 ///< Rayleigh b, s, >= 0
  Integrator integrator = Integrator::BackwardEuler;
  int newton_iterations = 1;                      ///< max Newton iterations per substep, >= 1
  /// Stop Newton early when the update's max node velocity change is <= tolerance (m/s);
  /// 0 = always run newton_iterations.
  double newton_tolerance = 0.0;
  LinearSolver solver = LinearSolver::Auto;
  double pcg_tolerance = 1e-8;                    ///< PCG stops at ||r||_2 <= tol ||b||_2
  int pcg_max_iterations = 1000;
  bool ground = false;                            ///< enable `ground_plane`
  GroundPlane ground_plane;
  /// A step fails when the total (kinetic + elastic) energy exceeds this (J). 0 = automatic:
  /// 1e6 * max_e(E_e) * total volume (a mean strain of about 1400) plus 20 times the poke
  /// springs' energy at the start of the substep. Meant to catch blow-ups, not large motions.
  double max_energy = 0.0;
};

/// Scripted rigid motion of a node set, from the node positions p0 at the time the handle is
/// added. start and stop are absolute simulation times (s); p0 is taken as the pose at `start`.
/// With s = clamp(t, start, stop) - start:
///   p(t) = center + velocity s + Rot(axis, angular_velocity s) (p0 - center)
/// so the rotation axis passes through `center` and travels with the translation. To start
/// moving at run time, set start = Simulator::time() (an earlier start makes the nodes jump to
/// the pose of the current time on the next step).
struct RigidMotion {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< m, a point on the rotation axis
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();   ///< direction (normalised); any if w = 0
  double angular_velocity = 0.0;                     ///< rad/s, right-handed about axis
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< m/s
  double start = 0.0;                                ///< s
  double stop = 1e300;                               ///< s, >= start
};

struct StepResult {
  bool success = true;
  std::string message;       ///< empty on success; else names the step number and the cause
  long step = 0;             ///< number of this step (1 = first step since construction/reset)
  double time = 0.0;         ///< s, simulated time after the step (unchanged on failure)
  int newton_iterations = 0; ///< summed over substeps
  int solver_iterations = 0; ///< PCG iterations summed over solves; 0 for LDLT
  /// With a potential (set_potential): halvings of the Newton step summed over substeps, and
  /// the incremental potential (J) of the last substep before its first and after each Newton
  /// iteration (never increasing). Empty without a potential.
  int line_search_halvings = 0;
  std::vector<double> incremental_potential;
  double assemble_ms = 0.0;  ///< forces, rotations, warped stiffness, constraints
  double solve_ms = 0.0;     ///< factorisation + solve (or PCG)
  double total_ms = 0.0;
};

/// A parallel loop for the simulator's element and node loops: loop(count, block, f) must call
/// f(begin, end) once for each block [k block, min((k + 1) block, count)) of [0, count), on any
/// threads in any order, and return when all are done. Every block writes results of its own and
/// sums are taken per block, then in block order, so the simulator's results are the same to the
/// bit for every loop (one thread or many). interp::parallel_for has this form.
using ParallelFor =
    std::function<void(long long count, long long block, const std::function<void(long long, long long)>& f)>;

struct StaticResult {
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;     ///< max free-node force imbalance at the end, N
  std::string message;
};

class Simulator {
 public:
  /// U n x 3 rest positions (m), T m x 4 tetrahedra. per_element: empty or m materials.
  /// Throws Error for degenerate elements, bad indices, non-finite input, bad material or
  /// parameters (naming what is wrong). The inputs are copied.
  Simulator(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
            const Material& material, const Parameters& params = {},
            const std::vector<Material>& per_element = {});
  ~Simulator();
  Simulator(Simulator&&) noexcept;
  Simulator& operator=(Simulator&&) noexcept;

  // ------------------------------------------------------------ handles
  // Every add_* returns a handle id (>= 0, never reused). A node may belong to at most one
  // fixed/kinematic handle at a time (Error otherwise).

  /// Nodes held at their current positions.
  int fix(const std::vector<int>& nodes);
  /// Nodes following `motion` from their current positions.
  int add_kinematic(const std::vector<int>& nodes, const RigidMotion& motion);
  /// Constant force (N) at a material point: element + barycentric coordinates (4, sum 1),
  /// spread to the corners with the barycentric weights.
  int add_point_force(int element, const Eigen::Vector4d& bary, const Eigen::Vector3d& force);
  void set_point_force(int handle, const Eigen::Vector3d& force);
  /// Zero-length spring (stiffness N/m) pulling a material point toward `target` (m); treated
  /// implicitly. Move the target every frame with set_poke_target.
  int add_poke(int element, const Eigen::Vector4d& bary, const Eigen::Vector3d& target,
               double stiffness);
  void set_poke_target(int handle, const Eigen::Vector3d& target);
  /// Removes any handle. Kinematic nodes become free with their current velocity.
  void remove(int handle);
  bool has_handle(int handle) const;

  /// An extra potential E(x) added to every step (method.md fact 14), or nullptr to remove it.
  /// With one, each Newton iteration adds its gradient and Hessian blocks and takes a
  /// backtracking line search on the incremental potential, so newton_iterations and
  /// newton_tolerance become a real Newton solve. Needs BackwardEuler and stiffness_damping =
  /// 0 (Error otherwise, here or in set_params): the other step equations are not the
  /// minimum of a potential. The simulator shares ownership; the potential must not change
  /// during a step.
  void set_potential(std::shared_ptr<Potential> potential);
  const std::shared_ptr<Potential>& potential() const;
  /// Whether nodes i and j share an element (the pattern Potential::hessian_blocks must keep).
  bool adjacent(int i, int j) const;

  /// Runs the element loops (assembly, elastic energy) and the solver's node loops (block
  /// products, PCG) on `loop`; an empty one (the default) runs them on the calling thread.
  void set_parallel_for(ParallelFor loop);

  // ------------------------------------------------------------ stepping
  /// Advances by params().dt. On failure (non-finite state, runaway energy, solver failure) the
  /// state stays at the last good step and the result says why.
  StepResult step();
  /// Static equilibrium under gravity, point forces, pokes and the handles at the current time
  /// (velocities set to 0): Newton iterations with the warped stiffness until the max free-node
  /// force imbalance is <= tolerance (N) or, if tolerance = 0, until either it is <= 1e-10 *
  /// (max |external force| + max elastic force at the first iterate) or the last update moved
  /// no node by more than 1e-13 * (rest bounding-box diagonal). Always uses LDLT (exact
  /// solves; slow beyond ~20K tetrahedra). Needs enough fixed/kinematic nodes or pokes to
  /// remove the rigid motions, else it reports failure. Failure leaves the state unchanged.
  StaticResult solve_static(int max_iterations = 100, double tolerance = 0.0);

  // ------------------------------------------------------------ state
  const Eigen::MatrixXd& positions() const;   ///< n x 3, m
  const Eigen::MatrixXd& velocities() const;  ///< n x 3, m/s
  void set_positions(const Eigen::Ref<const Eigen::MatrixXd>& X);   ///< n x 3, finite
  void set_velocities(const Eigen::Ref<const Eigen::MatrixXd>& V);  ///< n x 3, finite
  /// Back to rest positions, zero velocity, time 0, step 0. Handles stay (kinematic motions
  /// restart from the positions captured when they were added).
  void reset();
  double time() const;  ///< s
  long step_count() const;

  double kinetic_energy() const;  ///< J
  double elastic_energy() const;  ///< J, co-rotational
  /// Elastic node forces at the current positions (n x 3, N; minus the gradient of
  /// elastic_energy()), computed by the same code as in step(). For tests and diagnostics.
  Eigen::MatrixXd elastic_forces() const;
  /// Warped stiffness K_el = sum_e R_e K_e R_e^T at the current positions (3n x 3n, N/m,
  /// symmetric, dof 3 i + c = node i, axis c), assembled by the same code as the matrix of
  /// step() and solve_static(), without their mass, damping and poke terms and without the
  /// rows of fixed or kinematic nodes zeroed. It ignores dR/dx: equal to the Hessian of
  /// elastic_energy() at rigid motions of the rest shape only. For tests and diagnostics
  /// (allocates; changes no state).
  Eigen::SparseMatrix<double> stiffness() const;
  /// J, -sum_i m_i g . x_i (zero level at the origin).
  double gravity_energy() const;
  Eigen::Vector3d linear_momentum() const;   ///< kg m/s
  Eigen::Vector3d angular_momentum() const;  ///< kg m^2/s about the origin
  /// Total rest volume and current signed volume (sum of signed element volumes, positive
  /// orientation taken from the rest shape), m^3.
  double rest_volume() const;
  double volume() const;

  // ------------------------------------------------------------ mesh
  int nodes() const;
  int elements() const;
  const Eigen::MatrixXd& rest_positions() const;
  const Eigen::MatrixXi& tets() const;
  const Eigen::VectorXd& masses() const;  ///< lumped, kg
  const Parameters& params() const;
  /// Changes dt, damping, gravity, Newton settings, ground, solver (validated; the mesh
  /// stays).
  void set_params(const Parameters& params);
  /// Linear solver actually used (Auto resolved).
  LinearSolver solver() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mbi::sim
