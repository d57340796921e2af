// Analytic colliders (method.md fact 15): signed distances, gradients, motion, bad input.
#include <mbi/pipeline/colliders.hpp>

#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <limits>
#include <random>
#include <vector>

using namespace mbi::pipeline;

namespace {

std::vector<Collider> shapes() {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  return {Collider::plane({0.1, -0.2, 0.3}, {0.3, 2.0, -0.4}, 0.4), Collider::sphere({0.2, 0.1, -0.1}, 0.7),
          Collider::box({0.1, 0.2, 0.0}, {0.5, 0.3, 0.8}, R), Collider::capsule({-0.4, 0.0, 0.2}, {0.5, 0.3, -0.1}, 0.25)};
}

Collider moving(Collider c) {
  c.motion.center = {0.3, -0.1, 0.2};
  c.motion.axis = {0.2, 1.0, 0.3};
  c.motion.angular_velocity = 1.3;
  c.motion.velocity = {0.4, -0.2, 0.1};
  c.motion.start = 0.25;
  return c;
}

}  // namespace

TEST_CASE("colliders: signed distances at known points", "[pipeline][colliders]") {
  const Collider plane = Collider::plane({0, 1, 0}, {0, 2, 0});
  CHECK(signed_distance(plane, {5, 3, -2}, 0).value == Approx(2.0));
  CHECK(signed_distance(plane, {5, 0.5, -2}, 0).value == Approx(-0.5));
  CHECK(signed_distance(plane, {5, 3, -2}, 0).normal.isApprox(Eigen::Vector3d::UnitY()));
  const Collider ball = Collider::sphere({1, 0, 0}, 0.5);
  CHECK(signed_distance(ball, {1, 2, 0}, 0).value == Approx(1.5));
  CHECK(signed_distance(ball, {1.25, 0, 0}, 0).value == Approx(-0.25));
  const Collider box = Collider::box({0, 0, 0}, {1, 2, 3});
  CHECK(signed_distance(box, {0, 0, 2.5}, 0).value == Approx(-0.5));
  CHECK(signed_distance(box, {0, 0, 2.5}, 0).normal.isApprox(Eigen::Vector3d::UnitZ()));
  CHECK(signed_distance(box, {4, 6, 0}, 0).value == Approx(5.0));  // corner edge: (3, 4) away
  const Collider cap = Collider::capsule({0, 0, 0}, {0, 0, 2}, 0.5);
  CHECK(signed_distance(cap, {1, 0, 1}, 0).value == Approx(0.5));
  CHECK(signed_distance(cap, {0, 0, 3}, 0).value == Approx(0.5));
  CHECK(signed_distance(cap, {0, 0.1, -0.2}, 0).value == Approx(std::sqrt(0.05) - 0.5));
}

TEST_CASE("colliders: the normal is the unit gradient of the distance (finite differences), "
          "static and moving", "[pipeline][colliders]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (bool move : {false, true})
    for (const Collider& base : shapes()) {
      const Collider c = move ? moving(base) : base;
      check_collider(c, "collider");
      for (int k = 0; k < 200; ++k) {
        const Eigen::Vector3d p(u(rng), u(rng), u(rng));
        const double t = move ? 0.9 : 0.0;
        const Distance d = signed_distance(c, p, t);
        const double eps = 1e-6;
        Eigen::Vector3d fd;
        for (int a = 0; a < 3; ++a) {
          const Eigen::Vector3d e = eps * Eigen::Vector3d::Unit(a);
          fd(a) = (signed_distance(c, p + e, t).value - signed_distance(c, p - e, t).value) / (2 * eps);
        }
        CHECK(std::abs(d.normal.norm() - 1.0) <= 1e-12);
        CHECK((fd - d.normal).norm() <= 1e-6);
      }
    }
}

TEST_CASE("colliders: a moving collider is the static one moved rigidly, its velocity is the "
          "motion's derivative", "[pipeline][colliders]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const Collider& base : shapes()) {
    const Collider c = moving(base);
    const double t = 1.1, s = t - c.motion.start;
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(c.motion.angular_velocity * s, c.motion.axis.normalized()).toRotationMatrix();
    auto carried = [&](const Eigen::Vector3d& p0, double dt) {
      const Eigen::Matrix3d Rd =
          Eigen::AngleAxisd(c.motion.angular_velocity * (s + dt), c.motion.axis.normalized()).toRotationMatrix();
      return Eigen::Vector3d(c.motion.center + c.motion.velocity * (s + dt) + Rd * (p0 - c.motion.center));
    };
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector3d p0(u(rng), u(rng), u(rng));
      const Eigen::Vector3d p = carried(p0, 0.0);
      const Distance moved = signed_distance(c, p, t), still = signed_distance(base, p0, 0.0);
      CHECK(moved.value == Approx(still.value).margin(1e-12));
      CHECK((moved.normal - R * still.normal).norm() <= 1e-12);
      // Before start the collider is at its given pose.
      CHECK(signed_distance(c, p0, 0.0).value == Approx(still.value).margin(1e-12));
      const Eigen::Vector3d fd = (carried(p0, 1e-6) - carried(p0, -1e-6)) / 2e-6;
      CHECK((collider_velocity(c, p, t) - fd).norm() <= 1e-7);
    }
    CHECK(collider_velocity(c, Eigen::Vector3d::Zero(), 0.1).isZero());  // before start
    CHECK(collider_velocity(base, Eigen::Vector3d::Ones(), 5.0).isZero());  // static
  }
}

TEST_CASE("colliders: bad input is an Error naming the collider and the field",
          "[pipeline][colliders][errors]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(check_collider(Collider::sphere({0, 0, 0}, 0.5, nan), "collider 3"),
                    Catch::StartsWith("collider 3: friction must be finite and >= 0"));
  CHECK_THROWS_WITH(check_collider(Collider::sphere({0, 0, 0}, 0.5, -0.1), "c"), Catch::Contains("friction"));
  CHECK_THROWS_WITH(check_collider(Collider::sphere({0, 0, 0}, 0.0), "ball"),
                    Catch::StartsWith("ball: radius must be finite and > 0 m"));
  CHECK_THROWS_WITH(check_collider(Collider::capsule({0, 0, 0}, {1, 0, 0}, nan), "cap"), Catch::Contains("radius"));
  CHECK_THROWS_WITH(check_collider(Collider::capsule({0, 0, 0}, {nan, 0, 0}, 1), "cap"), Catch::Contains("end"));
  CHECK_THROWS_WITH(check_collider(Collider::plane({0, 0, 0}, {0, 0, 0}), "floor"),
                    Catch::StartsWith("floor: normal must be finite and non-zero"));
  CHECK_THROWS_WITH(check_collider(Collider::box({0, 0, 0}, {1, 0, 1}), "crate"), Catch::Contains("half_extents"));
  CHECK_THROWS_WITH(check_collider(Collider::box({0, 0, 0}, {1, 1, 1}, 2 * Eigen::Matrix3d::Identity()), "crate"),
                    Catch::Contains("axes must be a rotation"));
  CHECK_THROWS_WITH(check_collider(Collider::box({0, 0, 0}, {1, 1, 1}, -Eigen::Matrix3d::Identity()), "crate"),
                    Catch::Contains("axes must be a rotation"));
  Collider jumpy = Collider::sphere({0, 0, 0}, 1);
  jumpy.motion.velocity = {nan, 0, 0};
  CHECK_THROWS_WITH(check_collider(jumpy, "ball"), Catch::Contains("motion has a non-finite field"));
  jumpy.motion.velocity = {1, 0, 0};
  jumpy.motion.stop = -1;
  CHECK_THROWS_WITH(check_collider(jumpy, "ball"), Catch::Contains("stop is before start"));
  for (const Collider& c : shapes()) CHECK_NOTHROW(check_collider(c, "ok"));
}
