// The simulator's own assembly (Simulator::elastic_forces / stiffness, i.e. the code step() runs)
// against the tested mesh functions and against finite differences; the element kernels that
// both share.
#include <catch2/catch.hpp>
#include <common/node_vectors.hpp>

#include "sim_helpers.hpp"

#include <Eigen/Dense>
#include <random>

using namespace mbi::sim;
using mbi::test::flat;
using mbi::test::unflat;
using mbi::test::nodes_at;

namespace {

double max_abs(const Eigen::MatrixXd& A) { return A.cwiseAbs().maxCoeff(); }

// A small irregular box, 3 x 2 x 2 cells of 0.1 m (36 nodes, 72 tets), and a random
// co-rotational state: every coordinate moved by up to 0.02 m (strains of ~20%), then rotated
// by a random rotation and translated.
struct Fixture {
  mbi::test::Mesh M = [] {
    auto m = mbi::test::box_tet_mesh(3, 2, 2, Eigen::Vector3d(0.3, 0.2, 0.2));
    mbi::test::jitter(m, 0.2, 0.1, 7);
    return m;
  }();
  Material mat{2e5, 0.35, 1000.0};
  MeshRest rest = mesh_rest(M.U, M.T, mat);
  Eigen::Matrix3d R = mbi::test::random_rotation(3, 21);
  Eigen::RowVector3d t = Eigen::RowVector3d(0.4, -0.3, 1.1);

  Eigen::MatrixXd deformed(unsigned seed) const {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    Eigen::MatrixXd X = M.U;
    for (Eigen::Index i = 0; i < X.size(); ++i) X.data()[i] += 0.02 * uni(rng);
    return (X * R.transpose()).rowwise() + t;
  }
  Eigen::MatrixXd rigid() const { return (M.U * R.transpose()).rowwise() + t; }
};

// Central differences of the simulator's assembled forces: column d = -(f(q + h e_d) -
// f(q - h e_d)) / 2h, the Hessian of the energy.
Eigen::MatrixXd fd_stiffness(Simulator& sim, const Eigen::MatrixXd& X, double h) {
  const Eigen::VectorXd q = flat(X);
  Eigen::MatrixXd H(q.size(), q.size());
  for (Eigen::Index d = 0; d < q.size(); ++d) {
    Eigen::VectorXd qp = q, qm = q;
    qp(d) += h;
    qm(d) -= h;
    sim.set_positions(unflat(qp));
    const Eigen::VectorXd fp = flat(sim.elastic_forces());
    sim.set_positions(unflat(qm));
    const Eigen::VectorXd fm = flat(sim.elastic_forces());
    H.col(d) = -(fp - fm) / (2 * h);
  }
  sim.set_positions(X);
  return H;
}

}  // namespace

TEST_CASE("element kernels: the K_e v product and the 12x12 warped stiffness agree",
          "[sim][corot][assembly]") {
  Fixture fx;
  std::mt19937 rng(4);
  std::normal_distribution<double> g;
  for (int e = 0; e < static_cast<int>(fx.M.T.rows()); e += 7) {
    const TetRest& r = fx.rest.tets[e];
    const Eigen::Matrix3d R = mbi::test::random_rotation(3, 100 + e);
    Eigen::Matrix<double, 3, 4> v;
    for (int i = 0; i < 12; ++i) v.data()[i] = g(rng);
    const Eigen::Matrix<double, 12, 12> K = warped_tet_stiffness(r, fx.rest.lame[e], R);
    using Vec12 = Eigen::Matrix<double, 12, 1>;  // corner-major, as the 12x12 matrix
    const Vec12 Kv = K * Eigen::Map<const Vec12>(v.data());
    const Eigen::Matrix<double, 3, 4> prod =
        warped_tet_product(r.grad, r.volume, fx.rest.lame[e], R, v);
    CHECK((Eigen::Map<const Vec12>(prod.data()) - Kv).norm() < 1e-13 * K.norm() * v.norm());
    // R K R^T with K the rest stiffness, and symmetric.
    Eigen::Matrix<double, 12, 12> Rb = Eigen::Matrix<double, 12, 12>::Zero();
    for (int a = 0; a < 4; ++a) Rb.block<3, 3>(3 * a, 3 * a) = R;
    const Eigen::Matrix<double, 12, 12> K0 = linear_tet_stiffness(r, fx.rest.lame[e]);
    CHECK((K - Rb * K0 * Rb.transpose()).norm() < 1e-13 * K.norm());
    CHECK((K - K.transpose()).norm() < 1e-14 * K.norm());
  }
}

TEST_CASE("the simulator assembles exactly the tested forces and warped stiffness",
          "[sim][assembly]") {
  Fixture fx;
  const int n = static_cast<int>(fx.M.U.rows());
  Simulator sim(fx.M.U, fx.M.T, fx.mat);
  auto compare = [&](const Eigen::MatrixXd& X) {
    // Round-off only: the same kernels, summed in a different order.
    const Eigen::MatrixXd f = elastic_forces(fx.rest, fx.M.T, X);
    const Eigen::MatrixXd K = Eigen::MatrixXd(warped_stiffness(fx.rest, fx.M.T, X));
    const Eigen::MatrixXd Ks = Eigen::MatrixXd(sim.stiffness());
    REQUIRE(Ks.rows() == 3 * n);
    REQUIRE(Ks.cols() == 3 * n);
    CHECK(max_abs(sim.elastic_forces() - f) <= 1e-12 * max_abs(f));
    CHECK(max_abs(Ks - K) <= 1e-12 * max_abs(K));
    CHECK(sim.elastic_energy() == Approx(elastic_energy(fx.rest, fx.M.T, X)).epsilon(1e-12));
  };
  SECTION("first assembly (closed-form rotations)") {
    const Eigen::MatrixXd X = fx.deformed(1);
    sim.set_positions(X);
    CHECK(max_abs(sim.elastic_forces()) > 1.0);  // N: really loaded
    compare(X);
  }
  SECTION("during a simulation (rotations refined from the previous step)") {
    Simulator twin(fx.M.U, fx.M.T, fx.mat);
    for (Simulator* s : {&sim, &twin}) {
      s->fix(nodes_at(fx.M.U, 0, 0.0));
      s->add_poke(static_cast<int>(fx.M.T.rows()) - 1, Eigen::Vector4d(0.25, 0.25, 0.25, 0.25),
                  Eigen::Vector3d(0.6, 0.3, 0.1), 5e3);
    }
    for (int s = 0; s < 30; ++s) REQUIRE(sim.step().success);
    INFO("max displacement " << max_abs(sim.positions() - fx.M.U) << " m");
    CHECK(max_abs(sim.positions() - fx.M.U) > 0.05);  // m: large motion
    compare(sim.positions());
    // The accessors change no state (not even the rotations that warm-start the next
    // assembly): a twin that never calls them follows the same trajectory bit for bit.
    for (int s = 0; s < 30; ++s) REQUIRE(twin.step().success);
    for (int s = 0; s < 5; ++s) {
      (void)sim.stiffness();
      (void)sim.elastic_forces();
      REQUIRE(sim.step().success);
      REQUIRE(twin.step().success);
    }
    CHECK(sim.positions() == twin.positions());
  }
}

TEST_CASE("assembled stiffness vs finite differences of the assembled forces",
          "[sim][assembly][fd]") {
  // Central differences with step h = 1e-7 m (1e-6 of the cell size): truncation ~ (h/0.1)^2
  // ~ 1e-12 and round-off ~ 1e-16 |f| / h ~ 1e-10 relative to the largest stiffness entry, so a
  // tolerance of 1e-6 of the largest entry leaves a wide margin and still catches any missing
  // term (the dR/dx term that the warped stiffness drops is ~1e-1 of it at these strains).
  const double h = 1e-7, tol = 1e-6;
  Fixture fx;
  Simulator sim(fx.M.U, fx.M.T, fx.mat);
  SECTION("general state: the exact co-rotational Hessian is the derivative of the forces the "
          "simulator assembles; its warped stiffness is not") {
    const Eigen::MatrixXd X = fx.deformed(2);
    sim.set_positions(X);
    const Eigen::MatrixXd Hfd = fd_stiffness(sim, X, h);
    const Eigen::MatrixXd H = Eigen::MatrixXd(corotational_hessian(fx.rest, fx.M.T, X));
    const double scale = max_abs(H);
    INFO("max |H - H_fd| / max |H| = " << max_abs(H - Hfd) / scale);
    CHECK(max_abs(H - Hfd) <= tol * scale);
    // The warped stiffness ignores dR/dx: far outside the tolerance here, so the check above
    // would fail for it (and does distinguish the two matrices).
    const Eigen::MatrixXd Ks = Eigen::MatrixXd(sim.stiffness());
    INFO("max |K_warped - H_fd| / max |H| = " << max_abs(Ks - Hfd) / scale);
    CHECK(max_abs(Ks - Hfd) > 1e3 * tol * scale);
  }
  SECTION("rigidly rotated and translated rest shape: the warped stiffness is exact") {
    const Eigen::MatrixXd X = fx.rigid();
    sim.set_positions(X);
    CHECK(max_abs(sim.elastic_forces()) < 1e-9);  // N: no force under a rigid motion
    const Eigen::MatrixXd Hfd = fd_stiffness(sim, X, h);
    const Eigen::MatrixXd Ks = Eigen::MatrixXd(sim.stiffness());
    const double scale = max_abs(Ks);
    INFO("max |K - K_fd| / max |K| = " << max_abs(Ks - Hfd) / scale);
    CHECK(max_abs(Ks - Hfd) <= tol * scale);
    CHECK(max_abs(Ks - Ks.transpose()) <= 1e-14 * scale);
  }
}

TEST_CASE("with stiffness damping, converged backward Euler satisfies "
          "M (v+ - v) = h (f(x+) + m g - b K(x+) v+) with the assembled K",
          "[sim][assembly][integrator]") {
  // Checks the simulator's matrix-free K v (damping force) against its assembled matrix.
  const auto M = mbi::test::bar(8, 2, 2, 1.0, 0.25);
  const Material mat{2e4, 0.4, 1000};
  Parameters p;
  p.dt = 1.0 / 30.0;
  p.stiffness_damping = 0.05;
  p.newton_iterations = 100;
  p.newton_tolerance = 1e-12;  // m/s
  Simulator sim(M.U, M.T, mat, p);
  const auto fixed = nodes_at(M.U, 0, 0.0);
  sim.fix(fixed);
  std::vector<char> is_fixed(M.U.rows(), 0);
  for (int i : fixed) is_fixed[i] = 1;
  for (int s = 0; s < 8; ++s) {
    const Eigen::MatrixXd v0 = sim.velocities();
    const StepResult r = sim.step();
    REQUIRE(r.success);
    CHECK(r.newton_iterations < 100);
    const Eigen::MatrixXd f = sim.elastic_forces();
    const Eigen::VectorXd Kv = sim.stiffness() * flat(sim.velocities());
    double worst = 0.0, scale = 0.0, damping = 0.0;
    for (Eigen::Index i = 0; i < M.U.rows(); ++i) {
      if (is_fixed[i]) continue;
      const double m = sim.masses()(i);
      const Eigen::RowVector3d damp = p.stiffness_damping * Kv.segment<3>(3 * i).transpose();
      const Eigen::RowVector3d rhs = f.row(i) + m * p.gravity.transpose() - damp;
      worst = std::max(worst, (m * (sim.velocities().row(i) - v0.row(i)) - p.dt * rhs).norm());
      scale = std::max(scale, m * 9.81 * p.dt);
      damping = std::max(damping, p.dt * damp.norm());
    }
    CHECK(damping > 1e-3 * scale);  // the damping term matters
    CHECK(worst < 1e-8 * scale);
  }
}
