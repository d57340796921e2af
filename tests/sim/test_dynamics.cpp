// Time stepping: twisting bar (co-rotational vs linear baseline), momentum conservation, long
// runs, recovery from inversion, handles, failure guard, bad input.
#include <catch2/catch.hpp>

#include "sim_helpers.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>

using namespace mbi::sim;
using mbi::test::nodes_at;

namespace {
const double kPi = 3.14159265358979323846;

// Signed volume of the deformed mesh (rest orientation positive); `local` receives the
// volume-weighted mean of |V_e / V_e,rest - 1| (local volume error, no cancellation).
double mesh_volume(const mbi::test::Mesh& M, const Eigen::MatrixXd& X, double* local = nullptr) {
  double V = 0.0, V0 = 0.0, err = 0.0;
  for (Eigen::Index e = 0; e < M.T.rows(); ++e) {
    Eigen::Matrix3d D, Dm;
    for (int a = 0; a < 3; ++a) {
      D.col(a) = (X.row(M.T(e, a + 1)) - X.row(M.T(e, 0))).transpose();
      Dm.col(a) = (M.U.row(M.T(e, a + 1)) - M.U.row(M.T(e, 0))).transpose();
    }
    const double ve = std::abs(Dm.determinant()) / 6.0, J = D.determinant() / Dm.determinant();
    V += ve * J;
    V0 += ve;
    err += ve * std::abs(J - 1.0);
  }
  if (local) *local = err / V0;
  return V;
}
}  // namespace

TEST_CASE("twisting a bar by 180 degrees keeps its volume, linear FEM does not",
          "[sim][dynamics][twist][long]") {
  const double L = 1.0, h = 0.1;  // L / h = 10
  const auto M = mbi::test::bar(20, 2, 2, L, h);
  const Material mat{1e5, 0.45, 1000};
  Parameters p;
  p.gravity.setZero();
  p.mass_damping = 2.0;
  p.dt = 1.0 / 60.0;
  Simulator sim(M.U, M.T, mat, p);
  const auto left = nodes_at(M.U, 0, 0.0), right = nodes_at(M.U, 0, L);
  sim.fix(left);
  RigidMotion twist;
  twist.center = Eigen::Vector3d(L, h / 2, h / 2);
  twist.axis = Eigen::Vector3d::UnitX();
  twist.angular_velocity = kPi;  // 180 degrees in 1 s
  twist.stop = 1.0;
  sim.add_kinematic(right, twist);
  for (int s = 0; s < 180; ++s) REQUIRE(sim.step().success);  // 1 s twist + 2 s settling
  // The right end really turned by 180 degrees.
  const Eigen::Vector3d c(L, h / 2, h / 2);
  for (int i : right) {
    const Eigen::Vector3d r0 = M.U.row(i).transpose() - c, r1 = sim.positions().row(i).transpose() - c;
    CHECK((r1 - Eigen::Vector3d(r0.x(), -r0.y(), -r0.z())).norm() < 1e-12);
  }
  const double V0 = sim.rest_volume();
  double local_corot = 0.0, local_lin = 0.0;
  const double dv_corot = std::abs(mesh_volume(M, sim.positions(), &local_corot) / V0 - 1.0);
  CHECK(std::abs(sim.volume() / V0 - 1.0) == Approx(dv_corot).margin(1e-12));
  // Linear FEM baseline on the same set-up (static, same end conditions).
  Eigen::MatrixXd fixed_pos(left.size() + right.size(), 3);
  std::vector<int> fixed = left;
  fixed.insert(fixed.end(), right.begin(), right.end());
  for (size_t j = 0; j < fixed.size(); ++j)
    fixed_pos.row(j) = j < left.size() ? M.U.row(fixed[j]) : sim.positions().row(fixed[j]);
  const Eigen::MatrixXd Xlin =
      mbi::test::linear_static(M, mat, Eigen::Vector3d::Zero(), fixed, fixed_pos);
  const double dv_lin = std::abs(mesh_volume(M, Xlin, &local_lin) / V0 - 1.0);
  std::cout << "twist 180 deg, 20x2x2-cell bar L/h = 10: total volume change co-rotational "
            << 100 * dv_corot << " %, linear FEM " << 100 * dv_lin
            << " %; mean local |dV/V| co-rotational " << 100 * local_corot << " %, linear FEM "
            << 100 * local_lin << " %\n";
  CHECK(dv_corot < 0.05);
  CHECK(local_corot < 0.05);
  CHECK(dv_lin > 5 * dv_corot);
  CHECK(local_lin > 5 * local_corot);
}

TEST_CASE("free flight: momentum is conserved", "[sim][dynamics][momentum]") {
  auto M = mbi::test::box_tet_mesh(3, 2, 2, Eigen::Vector3d(0.6, 0.4, 0.4));
  mbi::test::jitter(M, 0.15, 0.2, 5);
  const Material mat{1e5, 0.4, 1000};
  const int n = static_cast<int>(M.U.rows());
  // Spin + drift + random deformation velocities (so elastic forces are active).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const Eigen::Vector3d w(0.7, -1.1, 2.0), drift(0.3, 0.1, -0.2);
  Eigen::MatrixXd V(n, 3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d r = M.U.row(i).transpose();
    V.row(i) = (w.cross(r) + drift + 0.2 * Eigen::Vector3d(uni(rng), uni(rng), uni(rng))).transpose();
  }
  SECTION("implicit midpoint: linear and angular momentum") {
    Parameters p;
    p.gravity.setZero();
    p.integrator = Integrator::ImplicitMidpoint;
    p.newton_iterations = 50;
    p.newton_tolerance = 1e-13;  // m/s
    Simulator sim(M.U, M.T, mat, p);
    sim.set_velocities(V);
    const Eigen::Vector3d P0 = sim.linear_momentum(), L0 = sim.angular_momentum();
    double emin = 1e300, emax = 0.0, elmax = 0.0;
    for (int s = 0; s < 60; ++s) {
      const StepResult r = sim.step();
      REQUIRE(r.success);
      CHECK(r.newton_iterations < 50);  // converged
      const double e = sim.kinetic_energy() + sim.elastic_energy();
      emin = std::min(emin, e);
      emax = std::max(emax, e);
      elmax = std::max(elmax, sim.elastic_energy());
    }
    INFO("relative drift after 60 steps: linear momentum "
         << (sim.linear_momentum() - P0).norm() / P0.norm() << ", angular momentum "
         << (sim.angular_momentum() - L0).norm() / L0.norm() << "; energy range "
         << (emax - emin) / emax);
    CHECK(elmax > 1e-3 * emax);  // elastic forces were really active
    CHECK((sim.linear_momentum() - P0).norm() < 1e-6 * P0.norm());
    CHECK((sim.angular_momentum() - L0).norm() < 1e-6 * L0.norm());
    CHECK(emax - emin < 0.05 * emax);  // no numerical damping to speak of
  }
  SECTION("backward Euler: linear momentum exactly, angular momentum decays slowly") {
    Parameters p;
    p.gravity.setZero();
    Simulator sim(M.U, M.T, mat, p);
    sim.set_velocities(V);
    const Eigen::Vector3d P0 = sim.linear_momentum(), L0 = sim.angular_momentum();
    const double E0 = sim.kinetic_energy();
    for (int s = 0; s < 60; ++s) REQUIRE(sim.step().success);
    INFO("after 60 steps: linear momentum drift "
         << (sim.linear_momentum() - P0).norm() / P0.norm() << ", |L| / |L0| = "
         << sim.angular_momentum().norm() / L0.norm());
    CHECK((sim.linear_momentum() - P0).norm() < 1e-10 * P0.norm());
    // O(dt^2 |w|^2) relative loss per step: 60 * (1/60)^2 * |w|^2 ~ 0.1
    CHECK((sim.angular_momentum() - L0).norm() < 0.2 * L0.norm());
    // Backward Euler dissipates: |L| and the energy go down, never up.
    CHECK(sim.angular_momentum().norm() < L0.norm());
    CHECK(sim.kinetic_energy() + sim.elastic_energy() < E0);
  }
}

TEST_CASE("10 s of a twisting bar at dt = 1/30 s stays finite with bounded energy",
          "[sim][dynamics][long]") {
  const double L = 1.0, h = 0.2;
  const auto M = mbi::test::bar(10, 2, 2, L, h);
  const Material mat{1e6, 0.45, 1000};
  Parameters p;
  p.dt = 1.0 / 30.0;
  Simulator sim(M.U, M.T, mat, p);
  sim.fix(nodes_at(M.U, 0, 0.0));
  RigidMotion twist;
  twist.center = Eigen::Vector3d(L, h / 2, h / 2);
  twist.angular_velocity = 2 * kPi / 10;  // one full turn over the 10 s
  sim.add_kinematic(nodes_at(M.U, 0, L), twist);
  // Bound: torsion theory energy G J theta^2 / (2 L) at the final angle (J = 0.141 h^4 for a
  // square), times 10, plus gravity sag energy (small).
  const double G = mat.youngs_modulus / (2 * 1.45);
  const double bound = 10 * G * 0.141 * std::pow(h, 4) * std::pow(2 * kPi, 2) / (2 * L) + 10.0;
  double emax = 0.0;
  for (int s = 0; s < 300; ++s) {
    const StepResult r = sim.step();
    REQUIRE(r.success);
    REQUIRE(sim.positions().allFinite());
    emax = std::max(emax, sim.kinetic_energy() + sim.elastic_energy());
  }
  INFO("max energy " << emax << " J, bound " << bound << " J");
  CHECK(emax < bound);
  CHECK(sim.time() == Approx(10.0).epsilon(1e-12));
}

TEST_CASE("squashed flat or inverted elements come back to the rest shape",
          "[sim][dynamics][inversion]") {
  const auto M = mbi::test::box_tet_mesh(2, 2, 2, Eigen::Vector3d(0.3, 0.3, 0.3));
  const Material mat{1e5, 0.4, 1000};
  Parameters p;
  p.gravity.setZero();
  p.mass_damping = 5.0;
  for (int mode = 0; mode < 3; ++mode) {
    Simulator sim(M.U, M.T, mat, p);
    Eigen::MatrixXd X = M.U;
    if (mode == 0) X.col(1).setConstant(0.1);   // flat: every element has zero volume
    if (mode == 1) X.col(1) *= -0.3;            // mirrored + squashed: every element inverted
    if (mode == 2) X.col(2) = 0.3 - 2.0 * X.col(2).array();  // inverted and stretched
    sim.set_positions(X);
    CHECK(sim.volume() <= 1e-12);
    for (int s = 0; s < 240; ++s) REQUIRE(sim.step().success);
    // Rest shape up to a rigid motion: zero elastic energy and unit Jacobian everywhere.
    CHECK(sim.elastic_energy() < 1e-8 * mat.youngs_modulus * sim.rest_volume());
    CHECK(sim.volume() == Approx(sim.rest_volume()).epsilon(1e-4));
    const double d0 = (M.U.row(0) - M.U.row(26)).norm();
    CHECK((sim.positions().row(0) - sim.positions().row(26)).norm() == Approx(d0).epsilon(1e-4));
  }
}

TEST_CASE("handles: kinematic motion, point forces, pokes, removal", "[sim][handles]") {
  const double L = 1.0, h = 0.1;
  const auto M = mbi::test::bar(10, 1, 1, L, h);
  const Material mat{1e6, 0.3, 1000};
  Parameters p;
  p.gravity.setZero();
  SECTION("kinematic nodes follow the scripted rigid motion exactly, then stop") {
    Simulator sim(M.U, M.T, mat, p);
    const auto right = nodes_at(M.U, 0, L);
    RigidMotion m;
    m.center = Eigen::Vector3d(L, 0, 0);
    m.axis = Eigen::Vector3d(1, 1, 0);
    m.angular_velocity = 0.8;
    m.velocity = Eigen::Vector3d(0.1, 0, -0.2);
    m.start = 0.1;
    m.stop = 0.5;
    const int id = sim.add_kinematic(right, m);
    for (int s = 0; s < 60; ++s) {
      REQUIRE(sim.step().success);
      const double t = sim.time();
      const double sdt = std::clamp(t, 0.1, 0.5) - 0.1;
      const Eigen::AngleAxisd rot(0.8 * sdt, Eigen::Vector3d(1, 1, 0).normalized());
      for (int i : right) {
        const Eigen::Vector3d expect =
            m.center + m.velocity * sdt + rot * (M.U.row(i).transpose() - m.center);
        REQUIRE((sim.positions().row(i).transpose() - expect).norm() < 1e-12);
      }
    }
    sim.remove(id);
    CHECK_FALSE(sim.has_handle(id));
    CHECK_THROWS_AS(sim.remove(id), Error);
    REQUIRE(sim.step().success);  // nodes are free now
  }
  SECTION("a point force on a free body gives momentum F dt per step") {
    Simulator sim(M.U, M.T, mat, p);
    const Eigen::Vector3d F(1.0, -2.0, 0.5);
    const int id = sim.add_point_force(5, Eigen::Vector4d(0.1, 0.2, 0.3, 0.4), F);
    for (int s = 0; s < 3; ++s) REQUIRE(sim.step().success);
    CHECK((sim.linear_momentum() - 3 * p.dt * F).norm() < 1e-10 * F.norm());
    sim.set_point_force(id, Eigen::Vector3d::Zero());
    const Eigen::Vector3d P = sim.linear_momentum();
    REQUIRE(sim.step().success);
    CHECK((sim.linear_momentum() - P).norm() < 1e-10 * F.norm());
  }
  SECTION("a poke spring pulls its material point toward a moving target") {
    Parameters pd = p;
    pd.mass_damping = 3.0;
    Simulator sim(M.U, M.T, mat, pd);
    sim.fix(nodes_at(M.U, 0, 0.0));
    const int e = static_cast<int>(M.T.rows()) - 1;
    const Eigen::Vector4d b(0.25, 0.25, 0.25, 0.25);
    Eigen::Vector3d p0 = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) p0 += b(a) * M.U.row(M.T(e, a)).transpose();
    const int poke = sim.add_poke(e, b, p0, 1e4);
    auto point = [&] {
      Eigen::Vector3d q = Eigen::Vector3d::Zero();
      for (int a = 0; a < 4; ++a) q += b(a) * sim.positions().row(M.T(e, a)).transpose();
      return q;
    };
    for (int s = 0; s < 120; ++s) {  // drag the target upward over 1 s, then hold
      sim.set_poke_target(poke, p0 + Eigen::Vector3d(0, 0.2 * std::min(1.0, s / 60.0), 0));
      REQUIRE(sim.step().success);
    }
    const double lift = point().y() - p0.y();
    CHECK(lift > 0.05);
    CHECK(lift < 0.2);
    // At rest the spring force balances the elastic force: spring stretch > 0.
    sim.remove(poke);
    for (int s = 0; s < 240; ++s) REQUIRE(sim.step().success);
    CHECK(std::abs(point().y() - p0.y()) < 0.1 * lift);  // springs back
  }
  SECTION("ground plane: a falling block stops on the ground") {
    Parameters pg;
    pg.ground = true;
    pg.ground_plane.offset = -0.5;
    pg.mass_damping = 1.0;
    Simulator sim(M.U, M.T, mat, pg);
    for (int s = 0; s < 120; ++s) {
      REQUIRE(sim.step().success);
      REQUIRE(sim.positions().col(1).minCoeff() >= -0.5 - 1e-12);
    }
    CHECK(sim.positions().col(1).minCoeff() == Approx(-0.5).margin(1e-9));
    CHECK(sim.kinetic_energy() < 1e-3);
  }
}

TEST_CASE("a failing step is reported with its number and the state is kept",
          "[sim][guard]") {
  const auto M = mbi::test::bar(4, 1, 1, 1.0, 0.25);
  Parameters p;
  p.max_energy = 1e-3;  // J: gravity makes this fail quickly
  Simulator sim(M.U, M.T, Material{1e5, 0.3, 1000}, p);
  sim.fix(nodes_at(M.U, 0, 0.0));
  StepResult r;
  int good = 0;
  Eigen::MatrixXd last;
  while ((r = sim.step()).success) {
    last = sim.positions();
    REQUIRE(++good < 1000);
  }
  CHECK(r.step == good + 1);
  CHECK_THAT(r.message, Catch::Contains("step " + std::to_string(good + 1)) &&
                           Catch::Contains("energy"));
  CHECK(sim.step_count() == good);
  CHECK(sim.time() == Approx(good * p.dt));
  if (good > 0) CHECK(sim.positions() == last);
  else CHECK(sim.positions() == M.U);
  sim.reset();
  CHECK(sim.positions() == M.U);
  CHECK(sim.time() == 0.0);
}

TEST_CASE("simulator rejects bad input with a clear error", "[sim][errors]") {
  const auto M = mbi::test::bar(2, 1, 1, 1.0, 0.5);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Material ok{1e5, 0.3, 1000};
  CHECK_THROWS_AS(Simulator(M.U, M.T, Material{0, 0.3, 1000}), Error);
  CHECK_THROWS_AS(Simulator(M.U, M.T, Material{1e5, 0.5, 1000}), Error);
  CHECK_THROWS_AS(Simulator(M.U, M.T, Material{1e5, -1.0, 1000}), Error);
  Eigen::MatrixXd Ubad = M.U;
  Ubad.row(M.T(1, 3)) = Ubad.row(M.T(1, 0));  // collapse element 1 (and its neighbours)
  CHECK_THROWS_WITH(Simulator(Ubad, M.T, ok), Catch::Contains("degenerate"));
  Parameters p;
  p.dt = 0;
  CHECK_THROWS_WITH(Simulator(M.U, M.T, ok, p), Catch::Contains("dt"));
  p = Parameters{};
  p.substeps = 0;
  CHECK_THROWS_AS(Simulator(M.U, M.T, ok, p), Error);
  Eigen::MatrixXd Uextra(M.U.rows() + 1, 3);
  Uextra << M.U, Eigen::RowVector3d(5, 5, 5);
  CHECK_THROWS_WITH(Simulator(Uextra, M.T, ok), Catch::Contains("node " + std::to_string(M.U.rows())));

  Simulator sim(M.U, M.T, ok);
  const Eigen::Vector4d b(0.25, 0.25, 0.25, 0.25);
  CHECK_THROWS_WITH(sim.add_point_force(0, b, Eigen::Vector3d(nan, 0, 0)),
                    Catch::Contains("not finite"));
  CHECK_THROWS_WITH(sim.add_point_force(99, b, Eigen::Vector3d(1, 0, 0)),
                    Catch::StartsWith("element 99"));
  CHECK_THROWS_AS(sim.add_point_force(0, Eigen::Vector4d(1, 1, 0, 0), Eigen::Vector3d(1, 0, 0)), Error);
  const int f = sim.add_point_force(0, b, Eigen::Vector3d(1, 0, 0));
  CHECK_THROWS_AS(sim.set_point_force(f, Eigen::Vector3d(0, nan, 0)), Error);
  CHECK_THROWS_AS(sim.add_poke(0, b, Eigen::Vector3d(0, 0, 0), -1.0), Error);
  const int pk = sim.add_poke(0, b, Eigen::Vector3d(0, 0, 0), 10.0);
  CHECK_THROWS_AS(sim.set_poke_target(pk, Eigen::Vector3d(nan, 0, 0)), Error);
  CHECK_THROWS_AS(sim.set_poke_target(f, Eigen::Vector3d(0, 0, 0)), Error);
  sim.fix({0, 1});
  CHECK_THROWS_WITH(sim.fix({1, 2}), Catch::Contains("node 1"));
  CHECK_THROWS_WITH(sim.fix({-1}), Catch::Contains("node -1"));
  Eigen::MatrixXd X = M.U;
  X(3, 2) = nan;
  CHECK_THROWS_WITH(sim.set_positions(X), Catch::Contains("node 3"));
  CHECK(sim.positions() == M.U);  // unchanged
  CHECK(sim.step().success);
}

TEST_CASE("PCG and LDLT give the same trajectory, Auto falls back to LDLT when PCG cannot "
          "converge",
          "[sim][solver][long]") {
  const auto M = mbi::test::bar(12, 3, 3, 1.0, 0.25);  // 13 x 4 x 4 nodes = 624 nodes
  const Material mat{1e5, 0.45, 1000};
  Parameters p;
  p.mass_damping = 0.5;
  p.stiffness_damping = 0.01;
  p.pcg_tolerance = 1e-12;
  p.solver = LinearSolver::LDLT;
  Simulator a(M.U, M.T, mat, p);
  p.solver = LinearSolver::PCG;
  Simulator b(M.U, M.T, mat, p);
  CHECK(a.solver() == LinearSolver::LDLT);
  CHECK(b.solver() == LinearSolver::PCG);
  for (Simulator* s : {&a, &b}) {
    s->fix(nodes_at(M.U, 0, 0.0));
    s->add_poke(static_cast<int>(M.T.rows()) - 1, Eigen::Vector4d(0.25, 0.25, 0.25, 0.25),
                Eigen::Vector3d(1.2, 0.5, 0.1), 50.0);
  }
  int pcg_iterations = 0;
  for (int s = 0; s < 40; ++s) {
    REQUIRE(a.step().success);
    const StepResult r = b.step();
    REQUIRE(r.success);
    pcg_iterations += r.solver_iterations;
  }
  CHECK(pcg_iterations > 0);
  const double swing = (a.positions() - M.U).cwiseAbs().maxCoeff();
  CHECK(swing > 0.05);
  CHECK((a.positions() - b.positions()).cwiseAbs().maxCoeff() < 1e-8 * swing);

  // A 1 mm bar with E = 1e9 Pa at dt = 1/60 s: h^2 K / M ~ 1e11, Jacobi-type PCG cannot reach
  // the tolerance within its iteration cap; Auto must still step correctly (LDLT).
  const auto S = mbi::test::bar(12, 3, 3, 1e-3, 2.5e-4);
  Parameters q;
  q.pcg_max_iterations = 50;
  Simulator c(S.U, S.T, Material{1e9, 0.45, 1000}, q);
  CHECK(c.solver() == LinearSolver::PCG);
  c.fix(nodes_at(S.U, 0, 0.0));
  for (int s = 0; s < 10; ++s) REQUIRE(c.step().success);
  CHECK(c.solver() == LinearSolver::LDLT);
  CHECK(c.positions().allFinite());
  q.solver = LinearSolver::PCG;  // forced PCG reports the failure instead
  Simulator d(S.U, S.T, Material{1e9, 0.45, 1000}, q);
  d.fix(nodes_at(S.U, 0, 0.0));
  bool failed = false;
  for (int s = 0; s < 10 && !failed; ++s) {
    const StepResult r = d.step();
    if (!r.success) {
      failed = true;
      CHECK_THAT(r.message, Catch::Contains("PCG"));
    }
  }
  CHECK(failed);
}

TEST_CASE("Newton iterations solve the backward Euler equations, substeps equal smaller steps",
          "[sim][integrator][long]") {
  auto M = mbi::test::bar(8, 2, 2, 1.0, 0.25);
  const Material mat{2e4, 0.4, 1000};  // soft: large deformation within a few steps
  SECTION("converged Newton satisfies M (v+ - v) = h (f(x+) + m g)") {
    Parameters p;
    p.dt = 1.0 / 30.0;
    p.newton_iterations = 100;
    p.newton_tolerance = 1e-12;
    Simulator sim(M.U, M.T, mat, p);
    const auto fixed = nodes_at(M.U, 0, 0.0);
    sim.fix(fixed);
    const MeshRest rest = mesh_rest(M.U, M.T, mat);
    for (int s = 0; s < 10; ++s) {
      const Eigen::MatrixXd v0 = sim.velocities();
      const StepResult r = sim.step();
      REQUIRE(r.success);
      CHECK(r.newton_iterations < 100);
      const Eigen::MatrixXd f = elastic_forces(rest, M.T, sim.positions());
      double worst = 0.0, scale = 0.0;
      for (Eigen::Index i = 0; i < M.U.rows(); ++i) {
        if (std::find(fixed.begin(), fixed.end(), i) != fixed.end()) continue;
        const Eigen::RowVector3d fi = f.row(i) + sim.masses()(i) * p.gravity.transpose();
        const Eigen::RowVector3d lhs = sim.masses()(i) * (sim.velocities().row(i) - v0.row(i));
        worst = std::max(worst, (lhs - p.dt * fi).norm());
        scale = std::max(scale, sim.masses()(i) * 9.81 * p.dt);
      }
      CHECK(worst < 1e-8 * scale);
    }
    CHECK(-mbi::test::tip_deflection(M.U, sim.positions(), 1.0) > 0.05);  // non-linear regime
  }
  SECTION("one step with 3 substeps equals 3 steps of dt / 3") {
    Parameters p;
    p.dt = 0.05;
    p.substeps = 3;
    p.stiffness_damping = 0.01;
    Simulator a(M.U, M.T, mat, p);
    p.dt = 0.05 / 3;
    p.substeps = 1;
    Simulator b(M.U, M.T, mat, p);
    a.fix(nodes_at(M.U, 0, 0.0));
    b.fix(nodes_at(M.U, 0, 0.0));
    for (int s = 0; s < 5; ++s) {
      REQUIRE(a.step().success);
      for (int k = 0; k < 3; ++k) REQUIRE(b.step().success);
    }
    CHECK(a.time() == Approx(b.time()).epsilon(1e-12));
    CHECK((a.positions() - b.positions()).cwiseAbs().maxCoeff() < 1e-10);
  }
  SECTION("with Rayleigh damping a released bar loses its energy, never gains") {
    Parameters p;
    p.gravity.setZero();
    p.mass_damping = 0.5;
    p.stiffness_damping = 0.02;
    Simulator sim(M.U, M.T, mat, p);
    sim.fix(nodes_at(M.U, 0, 0.0));
    Eigen::MatrixXd X = M.U;
    for (Eigen::Index i = 0; i < X.rows(); ++i) X(i, 1) += 0.2 * X(i, 0) * X(i, 0);  // bent
    sim.set_positions(X);
    const double E0 = sim.elastic_energy();
    double previous = E0;
    for (int s = 0; s < 300; ++s) {
      REQUIRE(sim.step().success);
      const double e = sim.kinetic_energy() + sim.elastic_energy();
      CHECK(e <= previous * (1 + 1e-9));
      previous = e;
    }
    CHECK(previous < 0.01 * E0);
  }
}

TEST_CASE("violent pokes and resets stay well-defined", "[sim][handles][robustness]") {
  const auto M = mbi::test::bar(10, 2, 2, 1.0, 0.1);
  Parameters p;
  p.dt = 1.0 / 30.0;
  Simulator sim(M.U, M.T, Material{1e5, 0.45, 1000}, p);
  sim.fix(nodes_at(M.U, 0, 0.0));
  RigidMotion spin;
  spin.center = Eigen::Vector3d(1.0, 0.05, 0.05);
  spin.angular_velocity = 2.0;
  const int kin = sim.add_kinematic(nodes_at(M.U, 0, 1.0), spin);
  // A very stiff poke whose target jumps 5 m away in one frame, then back, then removed.
  const int e = static_cast<int>(M.T.rows()) / 2;
  const int poke = sim.add_poke(e, Eigen::Vector4d(0.7, 0.1, 0.1, 0.1), Eigen::Vector3d(0.5, 5, 0), 1e7);
  for (int s = 0; s < 30; ++s) {
    if (s == 10) sim.set_poke_target(poke, Eigen::Vector3d(0.5, -3, 4));
    if (s == 20) sim.remove(poke);
    const StepResult r = sim.step();
    INFO("step " << s << ": " << r.message);
    REQUIRE(r.success);
    REQUIRE(sim.positions().allFinite());
    REQUIRE(sim.velocities().allFinite());
  }
  // reset(): rest state, time 0, handles kept; the scripted motion restarts from its pose.
  sim.reset();
  CHECK(sim.positions() == M.U);
  CHECK(sim.velocities().isZero(0));
  CHECK(sim.time() == 0.0);
  CHECK(sim.has_handle(kin));
  REQUIRE(sim.step().success);
  const int tip = nodes_at(M.U, 0, 1.0).front();
  const Eigen::AngleAxisd rot(2.0 * p.dt, Eigen::Vector3d::UnitX());
  const Eigen::Vector3d expect = spin.center + rot * (M.U.row(tip).transpose() - spin.center);
  CHECK((sim.positions().row(tip).transpose() - expect).norm() < 1e-12);
  // set_params changes dt and keeps the mesh; bad parameters are rejected.
  Parameters q = p;
  q.dt = 0.01;
  sim.set_params(q);
  REQUIRE(sim.step().success);
  CHECK(sim.time() == Approx(p.dt + 0.01));
  q.mass_damping = -1;
  CHECK_THROWS_WITH(sim.set_params(q), Catch::Contains("mass_damping"));
  CHECK(sim.params().dt == 0.01);
}
