// The simulator's extra potential (method.md fact 14): Newton with a line search on the
// incremental potential.
#include "sim_helpers.hpp"

#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

using namespace mbi::sim;
using mbi::test::MassSprings;
using mbi::test::WeakSprings;

namespace {

/// E = k/4 sum_i |x_i - c|^4 with a Hessian surrogate 10x too weak: full Newton steps overshoot.
struct WeakQuartic : Potential {
  double k = 0.0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double energy(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    double E = 0.0;
    for (Eigen::Index i = 0; i < x.size() / 3; ++i) E += 0.25 * k * std::pow((x.segment<3>(3 * i) - c).squaredNorm(), 2);
    return E;
  }
  void add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                    Eigen::Ref<Eigen::VectorXd> g) const override {
    for (Eigen::Index i = 0; i < x.size() / 3; ++i) {
      const Eigen::Vector3d d = x.segment<3>(3 * i) - c;
      g.segment<3>(3 * i) += k * d.squaredNorm() * d;
    }
  }
  void hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>& x,
                      std::vector<NodeBlock>& out) const override {
    for (Eigen::Index i = 0; i < x.size() / 3; ++i) {
      const Eigen::Vector3d d = x.segment<3>(3 * i) - c;
      out.push_back({int(i), int(i), 0.1 * k * d.squaredNorm() * Eigen::Matrix3d::Identity()});
    }
  }
};

/// IPC's barrier kappa b(d), b = -(d - dhat)^2 log(d / dhat), on every node's height d = y - wall
/// above a floor; max_step keeps a tenth of each node's height (`capped`), or admits all.
struct Floor : Potential {
  double wall = 0.0, dhat = 0.05, kappa = 0.0;
  bool capped = true;
  double energy(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    double E = 0.0;
    for (Eigen::Index i = 0; i < x.size() / 3; ++i) {
      const double d = x(3 * i + 1) - wall;
      if (d < dhat) E -= kappa * (d - dhat) * (d - dhat) * std::log(d / dhat);  // NaN below the floor
    }
    return E;
  }
  void add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    for (Eigen::Index i = 0; i < x.size() / 3; ++i) {
      const double d = x(3 * i + 1) - wall;
      if (d < dhat) g(3 * i + 1) += kappa * (-2 * (d - dhat) * std::log(d / dhat) - (d - dhat) * (d - dhat) / d);
    }
  }
  void hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>& x, std::vector<NodeBlock>& out) const override {
    for (Eigen::Index i = 0; i < x.size() / 3; ++i) {
      const double d = x(3 * i + 1) - wall;
      if (d >= dhat) continue;
      NodeBlock b{int(i), int(i), Eigen::Matrix3d::Zero()};
      b.value(1, 1) = kappa * (-2 * std::log(d / dhat) - 4 * (d - dhat) / d + (d - dhat) * (d - dhat) / (d * d));
      out.push_back(b);
    }
  }
  double max_step(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& dx) const override {
    double s = 1.0;
    for (Eigen::Index i = 0; capped && i < x.size() / 3; ++i)
      if (dx(3 * i + 1) < 0) s = std::min(s, 0.9 * (x(3 * i + 1) - wall) / -dx(3 * i + 1));
    return s;
  }
};

/// Records the times begin_substep is called with.
struct Recorder : MassSprings {
  std::vector<double> times;
  void begin_substep(double end_time, const Eigen::Ref<const Eigen::VectorXd>&,
                     const Eigen::Ref<const Eigen::VectorXd>&) override {
    times.push_back(end_time);
  }
};

/// Records the start and end times begin_substep_at is called with.
struct RecorderAt : MassSprings {
  std::vector<std::pair<double, double>> spans;
  void begin_substep_at(double start_time, double end_time, const Eigen::Ref<const Eigen::VectorXd>&,
                        const Eigen::Ref<const Eigen::VectorXd>&) override {
    spans.emplace_back(start_time, end_time);
  }
};

/// A block between two nodes that share no element.
struct OutsidePattern : MassSprings {
  int a = 0, b = 0;
  void hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>&,
                      std::vector<NodeBlock>& out) const override {
    out.push_back({a, b, Eigen::Matrix3d::Identity()});
  }
};

Eigen::VectorXd stacked(const Eigen::MatrixXd& X) {
  Eigen::VectorXd x(3 * X.rows());
  for (Eigen::Index i = 0; i < X.rows(); ++i) x.segment<3>(3 * i) = X.row(i).transpose();
  return x;
}

}  // namespace

TEST_CASE("potential: Newton with a quadratic potential reaches the analytic minimiser",
          "[sim][potential]") {
  const auto M = mbi::test::bar(4, 2, 2, 1.0, 0.25);
  Parameters p;
  p.gravity.setZero();
  p.newton_iterations = 30;
  p.newton_tolerance = 1e-12;
  Simulator sim(M.U, M.T, Material{1e5, 0.4, 1000}, p);
  // Start rigidly rotated, at rest; pull toward the same pose translated by d.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::MatrixXd X0 = M.U * R.transpose();
  sim.set_positions(X0);
  const Eigen::Vector3d d(0.3, -0.2, 0.5);
  const double k = 400.0;  // 1/s^2
  auto pot = std::make_shared<MassSprings>();
  pot->k_dof = k * stacked(sim.masses().replicate(1, 3));
  pot->target = stacked(X0.rowwise() + d.transpose());
  sim.set_potential(pot);
  const StepResult r = sim.step();
  REQUIRE(r.success);
  // m (v - 0) + h k m (h v - d) = 0 for every node: v = h k d / (1 + h^2 k), a translation.
  const double h = p.dt;
  const Eigen::Vector3d v = h * k * d / (1.0 + h * h * k);
  for (Eigen::Index i = 0; i < M.U.rows(); ++i) {
    CHECK((sim.velocities().row(i).transpose() - v).norm() <= 1e-9 * v.norm());
    CHECK((sim.positions().row(i) - X0.row(i)).transpose().isApprox(h * v, 1e-9));
  }
  CHECK(r.newton_iterations < 30);
  CHECK(r.incremental_potential.size() >= 2);
}

TEST_CASE("potential: the line search never increases the incremental potential",
          "[sim][potential]") {
  const auto M = mbi::test::bar(2, 1, 1, 1.0, 0.25);
  Parameters p;
  p.newton_iterations = 50;
  p.newton_tolerance = 1e-10;
  p.mass_damping = 0.5;
  Simulator sim(M.U, M.T, Material{2e4, 0.4, 1000}, p);
  sim.fix(mbi::test::nodes_at(M.U, 0, 0.0));
  auto pot = std::make_shared<WeakQuartic>();
  pot->k = 5e4;
  pot->c = Eigen::Vector3d(0.5, 2.0, 0.0);
  sim.set_potential(pot);
  int halvings = 0;
  for (int s = 0; s < 2; ++s) {
    const StepResult r = sim.step();
    REQUIRE(r.success);
    halvings += r.line_search_halvings;
    const auto& phi = r.incremental_potential;
    REQUIRE(phi.size() >= 2);
    for (size_t j = 1; j < phi.size(); ++j) CHECK(phi[j] <= phi[j - 1]);
  }
  CHECK(halvings > 0);  // the weak surrogate overshoots: the search had to act
}

TEST_CASE("potential: the converged step is a stationary point of the incremental potential "
          "(finite differences)", "[sim][potential]") {
  const auto M = mbi::test::bar(2, 1, 1, 1.0, 0.25);
  Parameters p;
  p.newton_iterations = 100;
  p.newton_tolerance = 1e-13;
  p.mass_damping = 0.3;
  const Material mat{2e4, 0.4, 1000};
  Simulator sim(M.U, M.T, mat, p);
  const auto fixed = mbi::test::nodes_at(M.U, 0, 0.0);
  sim.fix(fixed);
  auto pot = std::make_shared<WeakQuartic>();
  pot->k = 2e3;
  pot->c = Eigen::Vector3d(0.5, 1.0, 0.0);
  sim.set_potential(pot);
  REQUIRE(sim.step().success);
  const Eigen::VectorXd x0 = stacked(sim.positions()), v0 = stacked(sim.velocities());
  REQUIRE(sim.step().success);
  const Eigen::VectorXd v1 = stacked(sim.velocities());
  // Phi(v) = |v - v0|_M^2 / 2 + h a |v|_M^2 / 2 - h m g . v + E_el(x) + E(x), x = x0 + h v,
  // evaluated by a second simulator as a plain energy function.
  Simulator probe(M.U, M.T, mat, p);
  const Eigen::VectorXd m = stacked(sim.masses().replicate(1, 3));
  const double h = p.dt, a = p.mass_damping;
  const Eigen::VectorXd g = stacked(p.gravity.transpose().replicate(M.U.rows(), 1));
  auto phi = [&](const Eigen::VectorXd& vel) {
    const Eigen::VectorXd x = x0 + h * vel;
    Eigen::MatrixXd X(M.U.rows(), 3);
    for (Eigen::Index i = 0; i < X.rows(); ++i) X.row(i) = x.segment<3>(3 * i).transpose();
    probe.set_positions(X);
    const Eigen::VectorXd dv = vel - v0;
    return 0.5 * dv.dot(m.cwiseProduct(dv)) + 0.5 * h * a * vel.dot(m.cwiseProduct(vel)) -
           h * m.cwiseProduct(g).dot(vel) + probe.elastic_energy() + pot->energy(x);
  };
  std::vector<char> is_fixed(M.U.rows(), 0);
  for (int i : fixed) is_fixed[i] = 1;
  double worst = 0.0, scale = 0.0;
  const double eps = 1e-6;
  for (Eigen::Index dof = 0; dof < v1.size(); ++dof) {
    if (is_fixed[dof / 3]) continue;
    Eigen::VectorXd vp = v1, vm = v1;
    vp(dof) += eps;
    vm(dof) -= eps;
    worst = std::max(worst, std::abs(phi(vp) - phi(vm)) / (2 * eps));
    scale = std::max(scale, m(dof) * (std::abs(v1(dof) - v0(dof)) + h * 9.81));
  }
  CHECK(worst <= 1e-6 * scale);
  CHECK(scale > 0);
}

TEST_CASE("potential: bad Hessian pattern and incompatible parameters are refused",
          "[sim][potential][errors]") {
  const auto M = mbi::test::bar(4, 1, 1, 1.0, 0.25);
  Parameters p;
  Simulator sim(M.U, M.T, Material{}, p);
  auto pot = std::make_shared<OutsidePattern>();
  pot->k_dof = Eigen::VectorXd::Zero(3 * M.U.rows());
  pot->target = Eigen::VectorXd::Zero(3 * M.U.rows());
  pot->a = 0;
  pot->b = static_cast<int>(M.U.rows()) - 1;  // opposite corners of a 4-cell bar
  REQUIRE_FALSE(sim.adjacent(pot->a, pot->b));
  CHECK(sim.adjacent(M.T(0, 0), M.T(0, 3)));
  sim.set_potential(pot);
  const Eigen::MatrixXd X0 = sim.positions();
  const StepResult r = sim.step();
  CHECK_FALSE(r.success);
  CHECK(r.message.find("outside the element pattern") != std::string::npos);
  CHECK(sim.positions() == X0);
  Parameters mid = p;
  mid.integrator = Integrator::ImplicitMidpoint;
  CHECK_THROWS_WITH(sim.set_params(mid), "parameter integrator must be BackwardEuler with a potential");
  sim.set_potential(nullptr);
  sim.set_params(mid);
  CHECK_THROWS_WITH(sim.set_potential(pot), "parameter integrator must be BackwardEuler with a potential");
  CHECK(sim.step().success);
}

TEST_CASE("potential: begin_substep is told the end time of every substep, begin_substep_at "
          "its start too", "[sim][potential]") {
  const auto M = mbi::test::bar(2, 1, 1, 1.0, 0.25);
  Parameters p;
  p.substeps = 3;
  Simulator sim(M.U, M.T, Material{}, p);
  auto rec = std::make_shared<Recorder>();
  rec->k_dof = Eigen::VectorXd::Zero(3 * M.U.rows());
  rec->target = Eigen::VectorXd::Zero(3 * M.U.rows());
  sim.set_potential(rec);
  REQUIRE(sim.step().success);
  REQUIRE(sim.step().success);
  REQUIRE(rec->times.size() == 6);
  for (int k = 0; k < 6; ++k) CHECK(rec->times[k] == Approx((k + 1) * p.dt / 3));
  auto at = std::make_shared<RecorderAt>();  // the simulator calls begin_substep_at
  at->k_dof = rec->k_dof;
  at->target = rec->target;
  sim.set_potential(at);
  REQUIRE(sim.step().success);
  REQUIRE(at->spans.size() == 3);
  for (int k = 0; k < 3; ++k) {
    CHECK(at->spans[k].first == Approx((6 + k) * p.dt / 3));
    CHECK(at->spans[k].second == Approx((7 + k) * p.dt / 3));
  }
}

TEST_CASE("potential: every Newton step stays in the set max_step admits, and still converges",
          "[sim][potential]") {
  const auto M = mbi::test::bar(2, 1, 1, 1.0, 0.25);
  Parameters p;
  p.newton_iterations = 60;
  p.newton_tolerance = 1e-8;
  for (bool capped : {true, false}) {
    Simulator sim(M.U, M.T, Material{1e5, 0.3, 1000}, p);
    auto floor = std::make_shared<Floor>();
    floor->wall = -0.02;  // 2 cm below the bar, which falls at 3 m/s: 5 cm a step
    floor->kappa = 1e5;
    floor->capped = capped;
    sim.set_potential(floor);
    sim.set_velocities(Eigen::MatrixXd::Zero(M.U.rows(), 3).rowwise() + Eigen::RowVector3d(0, -3, 0));
    bool all_ok = true;
    int most = 0;
    for (int s = 0; s < 20 && all_ok; ++s) {
      const StepResult r = sim.step();
      all_ok = r.success;
      most = std::max(most, r.newton_iterations);
      if (capped) {
        INFO(r.message);
        REQUIRE(r.success);
        CHECK(sim.positions().col(1).minCoeff() > floor->wall);
        for (size_t j = 1; j < r.incremental_potential.size(); ++j)
          CHECK(r.incremental_potential[j] <= r.incremental_potential[j - 1]);
      }
    }
    if (capped) CHECK(most < 60);  // met the tolerance: the cap did not stall Newton
    else CHECK_FALSE(all_ok);      // negative control: the first guess lands below the floor
  }
}

TEST_CASE("potential: with the exact Hessian product, Newton on a weak surrogate converges in a "
          "few iterations to the same minimiser", "[sim][potential]") {
  const auto M = mbi::test::bar(4, 2, 2, 1.0, 0.25);
  Parameters p;
  p.gravity.setZero();
  p.newton_iterations = 60;
  p.newton_tolerance = 1e-10;  // m/s
  const Eigen::Vector3d d(0.3, -0.2, 0.5);
  // 1/s^2: h^2 k = 0.56, so blocks of a tenth of it make Newton's steps 1.47 times too long,
  // a linear rate of 0.47
  const double k = 2e3;
  auto run = [&](bool product) {
    Simulator sim(M.U, M.T, Material{1e5, 0.4, 1000}, p);
    auto pot = std::make_shared<WeakSprings>();
    pot->k_dof = k * stacked(sim.masses().replicate(1, 3));
    pot->target = stacked(M.U.rowwise() + d.transpose());
    pot->product = product;
    sim.set_potential(pot);
    const StepResult r = sim.step();
    REQUIRE(r.success);
    return std::make_pair(r.newton_iterations, stacked(sim.velocities()));
  };
  const auto [exact_iterations, exact] = run(true);
  const auto [weak_iterations, weak] = run(false);
  // m v + h k m (h v - d) = 0 for every node: v = h k d / (1 + h^2 k), a translation.
  const Eigen::Vector3d v = p.dt * k * d / (1.0 + p.dt * p.dt * k);
  for (Eigen::Index i = 0; i < M.U.rows(); ++i) {
    CHECK((exact.segment<3>(3 * i) - v).norm() <= 1e-9 * v.norm());
    CHECK((weak.segment<3>(3 * i) - v).norm() <= 1e-9 * v.norm());
  }
  CHECK(exact_iterations <= 3);
  CHECK(weak_iterations > 20);  // the blocks alone: about 35
}

TEST_CASE("potential: Newton's first guess extrapolates the last substep's change of velocity, and "
          "a state set from outside starts from the old velocity again", "[sim][potential]") {
  // Free fall over a floor far below (no energy there): v_n = n h g exactly, a translation the
  // elastic forces do not see. From rest the first iterate is the answer and the second Newton
  // update only confirms it (2 iterations); from the second step on the extrapolated guess is
  // the answer already (1 iteration).
  const auto M = mbi::test::bar(4, 2, 2, 1.0, 0.25);
  Parameters p;
  p.newton_iterations = 20;
  p.newton_tolerance = 1e-9;  // m/s
  Simulator sim(M.U, M.T, Material{1e5, 0.4, 1000}, p);
  auto floor = std::make_shared<Floor>();
  floor->wall = -100.0;
  floor->kappa = 1e3;
  sim.set_potential(floor);
  std::vector<int> iterations;
  for (int step = 1; step <= 5; ++step) {
    const StepResult r = sim.step();
    REQUIRE(r.success);
    iterations.push_back(r.newton_iterations);
    const Eigen::Vector3d v = step * p.dt * p.gravity;
    for (Eigen::Index i = 0; i < M.U.rows(); ++i) CHECK((sim.velocities().row(i).transpose() - v).norm() <= 1e-9 * v.norm());
  }
  CHECK(iterations == std::vector<int>{2, 1, 1, 1, 1});
  sim.set_velocities(sim.velocities());  // a velocity from outside: no last substep to extrapolate
  const StepResult r = sim.step();
  REQUIRE(r.success);
  CHECK(r.newton_iterations == 2);
}
