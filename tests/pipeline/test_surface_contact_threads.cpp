// SurfaceContact's per-point passes run on the library's threads (method.md fact 16): every
// result is the same, to the last bit, on 1, 2 and 3 threads.
#include <mbi/interp/threads.hpp>
#include <mbi/pipeline/surface_contact.hpp>

#include <catch2/catch.hpp>
#include "common/grid_meshes.hpp"

#include <cmath>
#include <memory>
#include <random>
#include <vector>

using namespace mbi::pipeline;

namespace {

/// What a contact gives in one substep of a sinking ball, to compare across thread counts.
struct ThreadsResult {
  double energy = 0, cap = 0, along = 0, start_cap = 0;
  int touching = 0, friction = 0;
  long long candidates = 0, move_candidates = 0, substep_points = 0;
  Eigen::VectorXd gradient, product;
  std::vector<mbi::sim::NodeBlock> blocks;
};

/// n points evenly on the unit sphere about centre (golden-angle spiral).
Eigen::MatrixXd threads_sphere(int n, const Eigen::Vector3d& centre) {
  Eigen::MatrixXd P(n, 3);
  for (int i = 0; i < n; ++i) {
    const double y = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - y * y), phi = 2.399963229728653 * i;
    P.row(i) = (centre + Eigen::Vector3d(r * std::cos(phi), y, r * std::sin(phi))).transpose();
  }
  return P;
}

/// A ball of 40,000 points in a 4^3-cell cage over a sliding plane with friction, the cage 15 cm
/// into it (a cap of 7.5% of the surface: thousands of candidates, several blocks a pass), on
/// `threads` threads: a substep's start, then energy, gradient, blocks, product, cap and line.
ThreadsResult threads_run(Method method, int threads) {
  mbi::interp::set_threads(threads);
  const mbi::test::Mesh mesh = mbi::test::box_tet_mesh(4, 4, 4, Eigen::Vector3d::Constant(2.2));
  DeformerOptions opt;
  opt.method = method;
  auto deformer = std::make_shared<Deformer>(mesh.U, mesh.T, threads_sphere(40000, Eigen::Vector3d::Constant(1.1)), opt);
  Collider plane = Collider::plane({0, 0.1, 0}, {0, 1, 0}, 0.5);
  plane.motion.velocity = Eigen::Vector3d(0.2, 0, 0.1);
  SurfaceContact contact(deformer, {plane, Collider::sphere({1.9, -0.05, 1.1}, 0.3, 0.2)}, 1e4);
  contact.set_max_depth(0.3);
  contact.set_friction_velocity(0.3);
  const Eigen::Index n = mesh.U.rows();
  Eigen::VectorXd x0(3 * n), sink(3 * n), v(3 * n);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> w(-1e-3, 1e-3);
  for (Eigen::Index i = 0; i < n; ++i) x0.segment<3>(3 * i) = mesh.U.row(i).transpose() - Eigen::Vector3d(0, 0.15, 0);
  for (Eigen::Index k = 0; k < sink.size(); ++k) sink(k) = w(rng) + (k % 3 == 1 ? -4e-3 : 0.0);
  for (Eigen::Index k = 0; k < v.size(); ++k) v(k) = w(rng);
  ThreadsResult r;
  contact.begin_substep_at(0.0, 0.01, x0, sink / 0.01);
  r.friction = contact.friction_pairs();
  r.start_cap = contact.max_step(x0, sink);
  const Eigen::VectorXd x = x0 + sink;
  r.energy = contact.energy(x);
  r.gradient = Eigen::VectorXd::Zero(3 * n);
  contact.add_gradient(x, r.gradient);
  contact.hessian_blocks(x, r.blocks);
  r.product = Eigen::VectorXd::Zero(3 * n);
  contact.add_hessian_product(x, v, r.product);
  r.touching = contact.touching(x);
  r.cap = contact.max_step(x, 40 * sink);
  contact.begin_line(x, 40 * sink);
  r.along = contact.energy_along(0.4);
  r.candidates = contact.counts().candidates;
  r.move_candidates = contact.counts().move_candidates;
  r.substep_points = contact.counts().substep_points;
  return r;
}

struct ThreadsRestore {
  ~ThreadsRestore() { mbi::interp::set_threads(0); }
};

}  // namespace

TEST_CASE("surface contact: the per-point passes give the same results, to the bit, on 1, 2 and 3 threads",
          "[pipeline][contact][threads]") {
  const ThreadsRestore restore;
  for (Method m : {Method::BI, Method::ModifiedBI}) {
    const ThreadsResult one = threads_run(m, 1);
    // enough points for several blocks of every pass, guarded points capped, friction
    REQUIRE(one.candidates > 4 * 512);
    REQUIRE(one.touching > 2000);
    REQUIRE(one.friction > 2000);
    REQUIRE(one.cap < 1.0);
    REQUIRE(one.blocks.size() > 100);
    REQUIRE(one.energy > 0);
    REQUIRE(one.along > 0);
    if (m != Method::BI) REQUIRE(one.product.norm() > 0);
    for (int threads : {2, 3}) {
      INFO("method " << method_name(m) << ", " << threads << " threads");
      const ThreadsResult r = threads_run(m, threads);
      CHECK(r.candidates == one.candidates);
      CHECK(r.move_candidates == one.move_candidates);
      CHECK(r.substep_points == one.substep_points);
      CHECK(r.friction == one.friction);
      CHECK(r.touching == one.touching);
      CHECK(r.energy == one.energy);
      CHECK(r.gradient == one.gradient);
      CHECK(r.product == one.product);
      CHECK(r.cap == one.cap);
      CHECK(r.start_cap == one.start_cap);
      CHECK(r.along == one.along);
      REQUIRE(r.blocks.size() == one.blocks.size());
      bool same = true;
      for (size_t i = 0; i < r.blocks.size(); ++i)
        same = same && r.blocks[i].row == one.blocks[i].row && r.blocks[i].col == one.blocks[i].col &&
               r.blocks[i].value == one.blocks[i].value;
      CHECK(same);
    }
  }
}
