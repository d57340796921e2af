// SurfaceContact::set_collider: a contact whose collider is moved between steps (the viewer's
// drag) evaluates as a fresh one given the same collider, whatever it evaluated before (its
// broad phase forgets the old pose); bad input is refused naming the collider.
#include <mbi/error.hpp>
#include <mbi/pipeline/surface_contact.hpp>

#include <catch2/catch.hpp>
#include "common/grid_meshes.hpp"

#include <memory>
#include <random>

using namespace mbi::pipeline;

TEST_CASE("set_collider: a moved collider evaluates as in a fresh contact", "[pipeline][contact]") {
  const mbi::test::Mesh mesh = mbi::test::box_tet_mesh(3, 2, 2, Eigen::Vector3d(1.5, 1.0, 1.0));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd P(200, 3);
  for (int p = 0; p < 200; ++p) P.row(p) = Eigen::RowVector3d(1.5 * u(rng), u(rng), u(rng));
  Eigen::VectorXd x(3 * mesh.U.rows());
  for (Eigen::Index i = 0; i < mesh.U.rows(); ++i) x.segment<3>(3 * i) = mesh.U.row(i).transpose() + Eigen::Vector3d(0, 0.02 * u(rng), 0);
  const Eigen::VectorXd dx = Eigen::VectorXd::Constant(x.size(), -0.05);
  auto deformer = std::make_shared<Deformer>(mesh.U, mesh.T, P, DeformerOptions{});
  const Collider floor = Collider::plane({0, -0.5, 0}, {0, 1, 0});
  const Collider away = Collider::sphere({4, 0.5, 0.5}, 0.4, 0.3);
  Collider into = Collider::sphere({1.5, 0.5, 0.5}, 0.4, 0.3);  // overlaps the box: not at rest
  into.motion.velocity = {-1, 0, 0};
  into.motion.start = 0.1;
  SurfaceContact moved(deformer, {floor, away}, 1e4), built(deformer, {floor, away}, 1e4);  // built: never evaluated
  moved.begin_substep_at(0.0, 0.1, x, Eigen::VectorXd::Zero(x.size()));
  CHECK(moved.touching(x) == 0);
  CHECK(moved.energy(x) == 0);
  moved.set_collider(1, into);
  built.set_collider(1, into);
  CHECK(moved.touching(x) > 10);  // at once, before a substep: nothing of the old pose kept
  CHECK(moved.touching(x) == built.touching(x));
  for (SurfaceContact* c : {&moved, &built}) c->begin_substep_at(0.1, 0.2, x, Eigen::VectorXd::Zero(x.size()));
  CHECK(moved.touching(x) > 10);
  CHECK(moved.touching(x) == built.touching(x));
  CHECK(moved.energy(x) > 0);
  CHECK(moved.energy(x) == Approx(built.energy(x)).epsilon(1e-12));
  Eigen::VectorXd gm = Eigen::VectorXd::Zero(x.size()), gb = gm;
  moved.add_gradient(x, gm);
  built.add_gradient(x, gb);
  CHECK((gm - gb).norm() <= 1e-12 * gb.norm());
  CHECK(moved.friction_pairs() == built.friction_pairs());
  CHECK(moved.max_step(x, dx) == Approx(built.max_step(x, dx)));
  CHECK_THROWS_WITH(moved.set_collider(2, away), Catch::Contains("collider 2 out of range"));
  CHECK_THROWS_WITH(moved.set_collider(0, Collider::sphere({0, 0, 0}, -1)), Catch::Contains("collider 0"));
}
