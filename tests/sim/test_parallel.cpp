// The simulator's parallel loop (Simulator::set_parallel_for): any loop gives the same bits.
#include "sim_helpers.hpp"

#include <catch2/catch.hpp>
#include <algorithm>
#include <atomic>
#include <thread>

using namespace mbi::sim;

namespace {

/// The blocks in reverse order on this thread.
void reverse_loop(long long count, long long block, const std::function<void(long long, long long)>& f) {
  for (long long b = (count - 1) / block * block; b >= 0; b -= block) f(b, std::min(b + block, count));
}

/// The blocks on 3 threads, each taking the next block as it comes.
void team_loop(long long count, long long block, const std::function<void(long long, long long)>& f) {
  std::atomic<long long> next{0};
  auto work = [&] {
    for (long long b; (b = next.fetch_add(block)) < count;) f(b, std::min(b + block, count));
  };
  std::thread a(work), b(work);
  work();
  a.join();
  b.join();
}

struct Trajectory {
  Eigen::MatrixXd X, V, forces;
  Eigen::SparseMatrix<double> K;
  int newton = 0, pcg = 0;
};

/// A bar twisted at one end and pulled by WeakSprings (blocks a third of the Hessian), 4 steps of 2 substeps on PCG.
Trajectory twisted_bar(const ParallelFor& loop) {
  const auto M = mbi::test::bar(12, 3, 3, 1.0, 0.25);
  Parameters p;
  p.substeps = 2;
  p.solver = LinearSolver::PCG;
  p.newton_iterations = 6;
  p.newton_tolerance = 1e-9;  // m/s
  p.mass_damping = 0.5;
  Simulator sim(M.U, M.T, Material{1e5, 0.4, 1000}, p);
  sim.set_parallel_for(loop);
  RigidMotion twist;
  twist.axis = Eigen::Vector3d::UnitX();
  twist.center = Eigen::Vector3d(1.0, 0.125, 0.125);
  twist.angular_velocity = 6.0;
  sim.add_kinematic(mbi::test::nodes_at(M.U, 0, 1.0), twist);
  sim.fix(mbi::test::nodes_at(M.U, 0, 0.0));
  auto springs = std::make_shared<mbi::test::WeakSprings>();
  springs->fraction = 1.0 / 3.0;
  springs->k_dof = Eigen::VectorXd::Constant(3 * M.U.rows(), 50.0);
  springs->target = Eigen::Map<const Eigen::VectorXd>(Eigen::MatrixXd((M.U.rowwise() + Eigen::RowVector3d(0, -0.1, 0)).transpose()).data(), 3 * M.U.rows());
  sim.set_potential(springs);
  Trajectory t;
  for (int step = 0; step < 4; ++step) {
    const StepResult r = sim.step();
    REQUIRE(r.success);
    t.newton += r.newton_iterations;
    t.pcg += r.solver_iterations;
  }
  t.X = sim.positions();
  t.V = sim.velocities();
  t.forces = sim.elastic_forces();
  t.K = sim.stiffness();
  return t;
}

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && (a.array() == b.array()).all();
}

}  // namespace

TEST_CASE("parallel loops: steps, forces and stiffness are the same to the bit on every loop", "[sim][parallel]") {
  const Trajectory one = twisted_bar({});
  REQUIRE(one.pcg > 0);
  for (const ParallelFor& loop : {ParallelFor(reverse_loop), ParallelFor(team_loop)}) {
    const Trajectory t = twisted_bar(loop);
    CHECK(t.newton == one.newton);
    CHECK(t.pcg == one.pcg);
    CHECK(same_bits(t.X, one.X));
    CHECK(same_bits(t.V, one.V));
    CHECK(same_bits(t.forces, one.forces));
    CHECK(same_bits(Eigen::MatrixXd(t.K), Eigen::MatrixXd(one.K)));
  }
}
