// The poke: the spring's stiffness gives one period whatever the mass; the drag plane's target
// lies on the ray and on the plane, bounded; grab() finds the material point under a hit.
#include <catch2/catch.hpp>

#include <mbi/interact/error.hpp>
#include <mbi/interact/poke.hpp>

#include "common/grid_meshes.hpp"

#include <cmath>
#include <limits>
#include <random>

using namespace mbi::interact;

namespace {
const double kPi = std::acos(-1.0);
}

TEST_CASE("poke spring: k = m (2 pi / period)^2, so the pull's period does not depend on mass", "[interact]") {
  for (double mass : {1e-6, 1e-3, 1.0, 1e4})
    for (double period : {0.02, 0.15, 1.0}) {
      const double k = poke_stiffness(mass, period);
      CHECK(2 * kPi * std::sqrt(mass / k) == Approx(period));  // the spring-mass period
      // the force k d on the grabbed point: along the displacement, k times its length
      const Eigen::Vector3d d(0.3, -0.4, 1.2);
      const Eigen::Vector3d force = k * d;
      CHECK(force.normalized().dot(d.normalized()) == Approx(1));
      CHECK(force.norm() == Approx(mass * std::pow(2 * kPi / period, 2) * d.norm()));
    }
  CHECK(poke_stiffness(-1, 0.15) == 0);                           // no negative spring
  CHECK(std::isfinite(poke_stiffness(1, 0)));                     // a zero period is bounded
  CHECK(poke_stiffness(1, 0) == Approx(poke_stiffness(1, 1e-6)));
}

TEST_CASE("drag plane: the target is where the ray meets the plane through the grab, bounded", "[interact]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector3d grab(u(rng), u(rng), u(rng)), normal(u(rng), u(rng), 1.5);
    const Ray ray{grab + Eigen::Vector3d(u(rng), u(rng), -3), Eigen::Vector3d(0.2 * u(rng), 0.2 * u(rng), 1)};
    const Eigen::Vector3d t = poke_target(ray, grab, normal, 1e9);
    INFO(k);
    CHECK(std::abs((t - grab).dot(normal.normalized())) < 1e-12);                         // on the plane
    CHECK(((t - ray.origin).cross(ray.direction)).norm() < 1e-12 * (t - ray.origin).norm());  // on the ray
    // bounded: the same direction from the grab, at most max_distance away
    const double reach = 0.5 * (t - grab).norm();
    const Eigen::Vector3d b = poke_target(ray, grab, normal, reach);
    CHECK((b - grab).norm() == Approx(reach));
    CHECK((b - grab).normalized().dot((t - grab).normalized()) == Approx(1));
    // the ray's length does not matter
    const Ray tiny{ray.origin, 1e-15 * ray.direction};
    CHECK((poke_target(tiny, grab, normal, 1e9) - t).norm() < 1e-12);
  }
  // a perspective camera: the plane facing the ray itself is the closest point of the ray
  const Eigen::Vector3d grab(0.2, 0.1, 0.3);
  const Ray r{Eigen::Vector3d(1, 2, -4), Eigen::Vector3d(-0.1, -0.3, 1)};
  const Eigen::Vector3d c = poke_target(r, grab, r.direction, 10);
  CHECK((c - grab).dot(r.direction) == Approx(0).margin(1e-12));
}

TEST_CASE("drag plane: parallel or runaway rays keep the grab, bad arguments are errors", "[interact]") {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d grab(1, 2, 3), n(0, 0, 1);
  CHECK(poke_target({Eigen::Vector3d(0, 0, 9), Eigen::Vector3d(1, 0, 0)}, grab, n, 2) == grab);    // parallel
  CHECK(poke_target({Eigen::Vector3d(inf, 0, -9), Eigen::Vector3d(0, 0, 1)}, grab, n, 2) == grab);  // far off
  CHECK(poke_target({Eigen::Vector3d(nan, 0, -9), Eigen::Vector3d(0, 0, 1)}, grab, n, 2) == grab);
  const Ray good{Eigen::Vector3d(0, 0, -9), Eigen::Vector3d(0, 0, 1)};
  CHECK_THROWS_WITH(poke_target({good.origin, Eigen::Vector3d::Zero()}, grab, n, 2), Catch::Contains("direction"));
  CHECK_THROWS_AS(poke_target({good.origin, Eigen::Vector3d(nan, 0, 1)}, grab, n, 2), Error);
  CHECK_THROWS_WITH(poke_target(good, grab, Eigen::Vector3d::Zero(), 2), Catch::Contains("normal"));
  CHECK_THROWS_WITH(poke_target(good, Eigen::Vector3d(nan, 0, 0), n, 2), Catch::Contains("grabbed point"));
  CHECK_THROWS_WITH(poke_target(good, grab, n, -1), Catch::Contains("max_distance"));
  CHECK_THROWS_WITH(poke_target(good, grab, n, nan), Catch::Contains("max_distance"));
}

TEST_CASE("grab: the material point under a hit, its control element and its spring", "[interact]") {
  const mbi::test::Mesh cage = mbi::test::box_tet_mesh(2, 2, 2, Eigen::Vector3d(2, 1, 1));
  // the dense surface: the cage's top face (y = 1) as two triangles, deformed by a shift
  Eigen::MatrixXd V(4, 3);
  V << 0, 1, 0, 2, 1, 0, 2, 1, 1, 0, 1, 1;
  Eigen::MatrixXi F(2, 3);
  F << 0, 2, 1, 0, 3, 2;
  const Eigen::VectorXd masses = Eigen::VectorXd::LinSpaced(cage.U.rows(), 0.1, 1.0);
  Hit hit;
  hit.face = 1;
  hit.bary = Eigen::Vector3d(0.2, 0.3, 0.5);
  hit.point = Eigen::Vector3d(5, 5, 5);  // where it is drawn, deformed
  const Grab g = grab(hit, V, F, cage.U, cage.T, masses, 0.15);
  const Eigen::Vector3d rest = 0.2 * V.row(0) + 0.3 * V.row(3) + 0.5 * V.row(2);
  Eigen::Vector3d embedded = Eigen::Vector3d::Zero();
  double mass = 0;
  for (int k = 0; k < 4; ++k) {
    embedded += g.bary(k) * cage.U.row(cage.T(g.element, k)).transpose();
    mass += masses(cage.T(g.element, k));
  }
  CHECK((embedded - rest).norm() < 1e-12);  // the same material point, in the control mesh
  CHECK(g.bary.minCoeff() >= -1e-12);
  CHECK(g.point == hit.point);               // the spring starts slack, at the drawn point
  CHECK(g.stiffness == Approx(poke_stiffness(mass, 0.15)));
  hit.face = 2;
  CHECK_THROWS_WITH(grab(hit, V, F, cage.U, cage.T, masses, 0.15), Catch::Contains("face 2"));
  hit.face = 0;
  CHECK_THROWS_WITH(grab(hit, V, F, cage.U, cage.T, masses.head(3), 0.15), Catch::Contains("masses"));
  CHECK_THROWS_WITH(grab(hit, V, F, cage.U, cage.T.leftCols(3), masses, 0.15), Catch::Contains("4 columns"));
}
