// The per-point laws of surface contact (method.md fact 17): normal energy, smoothed friction,
// conservative advancement.
#include <mbi/pipeline/contact_laws.hpp>

#include <catch2/catch.hpp>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>

using namespace mbi::pipeline;

TEST_CASE("contact laws: the normal energy's derivatives are finite differences, it is convex, "
          "k d^2 / 2 near 0, and finite beyond the depth", "[pipeline][contact][laws]") {
  const double k = 3e4, depth = 2e-3, inf = std::numeric_limits<double>::infinity();
  for (double D : {depth, inf})
    for (double d : {-1e-9, -1e-6, -2e-4, -1e-3, -1.9e-3, -1.985e-3, -1.995e-3, -3e-3}) {
      const contact::Law L = contact::normal_energy(d, k, D);
      const double e = 1e-6 * std::abs(d);
      const contact::Law Lp = contact::normal_energy(d + e, k, D), Lm = contact::normal_energy(d - e, k, D);
      INFO("d = " << d << ", depth = " << D);
      REQUIRE(std::isfinite(L.value));
      CHECK(L.slope == Approx((Lp.value - Lm.value) / (2 * e)).epsilon(1e-6));
      CHECK(L.curvature == Approx((Lp.slope - Lm.slope) / (2 * e)).epsilon(1e-6));
      CHECK(L.curvature >= k);
      CHECK(L.value >= 0.5 * k * d * d * (1 - 1e-12));
    }
  CHECK(contact::normal_energy(-1e-7, k, depth).value == Approx(0.5 * k * 1e-14).epsilon(1e-4));
  CHECK(contact::normal_energy(0.0, k, depth).value == 0.0);
  CHECK(contact::normal_energy(1e-3, k, depth).slope == 0.0);
  // Across the series switch (z = 1e-3) and the continuation (z = 0.99): continuous.
  for (double z : {1e-3, 0.99}) {
    const contact::Law a = contact::normal_energy(-z * depth * (1 - 1e-12), k, depth);
    const contact::Law b = contact::normal_energy(-z * depth * (1 + 1e-12), k, depth);
    CHECK(a.value == Approx(b.value).epsilon(1e-9));
    CHECK(a.slope == Approx(b.slope).epsilon(1e-9));
    CHECK(a.curvature == Approx(b.curvature).epsilon(1e-9));
  }
}

TEST_CASE("contact laws: smoothed friction is C1, its Hessian is the finite difference of its "
          "gradient and PSD", "[pipeline][contact][laws]") {
  const double eps = 1e-3;
  CHECK(contact::friction_f0(eps * (1 - 1e-12), eps) == Approx(eps).epsilon(1e-9));
  CHECK(contact::friction_f1_over_y(eps * (1 - 1e-12), eps) * eps == Approx(1.0).epsilon(1e-9));
  CHECK(contact::friction_f1_over_y(0.0, eps) == Approx(2 / eps));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(0, 6.283);
  for (double y : {0.0, 1e-5, 3e-4, 0.9e-3, 1.5e-3, 0.1}) {
    const double a = angle(rng);
    const Eigen::Vector2d u = y * Eigen::Vector2d(std::cos(a), std::sin(a));
    const Eigen::Matrix2d H = contact::friction_hessian(u, eps);
    auto grad = [&](const Eigen::Vector2d& w) { return (contact::friction_f1_over_y(w.norm(), eps) * w).eval(); };
    Eigen::Matrix2d fd;
    const double h = 1e-9;
    for (int c = 0; c < 2; ++c) {
      Eigen::Vector2d up = u, um = u;
      up(c) += h;
      um(c) -= h;
      fd.col(c) = (grad(up) - grad(um)) / (2 * h);
      // The gradient is the finite difference of f0.
      CHECK(grad(u)(c) == Approx((contact::friction_f0(up.norm(), eps) - contact::friction_f0(um.norm(), eps)) / (2 * h))
                              .margin(1e-6));
    }
    INFO("|u| = " << y);
    CHECK((fd - H).norm() <= 1e-5 * H.norm());
    CHECK(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(H).eigenvalues().minCoeff() >= -1e-9 * H.norm());
  }
}

TEST_CASE("contact laws: conservative advancement never lets a point pass the depth, and keeps a "
          "tenth of its room", "[pipeline][contact][laws]") {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  Collider moving = Collider::capsule({-0.3, 0, 0}, {0.3, 0.1, 0}, 0.2);
  moving.motion.velocity = Eigen::Vector3d(0.5, 0, 0);
  moving.motion.angular_velocity = 2.0;
  moving.motion.axis = Eigen::Vector3d(0, 0, 1);
  const std::vector<Collider> shapes = {Collider::plane({0, 0, 0}, {0.2, 1, 0}), Collider::sphere({0, 0, 0}, 0.3),
                                        Collider::box({0, 0, 0}, {0.4, 0.05, 0.3}, R), moving};
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1, 1);
  const double depth = 0.01, time = 0.3;
  int capped = 0;
  for (const Collider& c : shapes)
    for (int trial = 0; trial < 100; ++trial) {
      const Eigen::Vector3d p(u(rng), u(rng), u(rng)), dp = 1.5 * Eigen::Vector3d(u(rng), u(rng), u(rng));
      const double room0 = signed_distance(c, p, time).value + depth;
      if (room0 <= 0) {
        CHECK(contact::advance(c, p, dp, time, depth) == 1.0);  // not guarded
        continue;
      }
      const double s = contact::advance(c, p, dp, time, depth);
      REQUIRE(s >= 0);
      REQUIRE(s <= 1);
      if (s < 1) {
        ++capped;
        CHECK(s > 0);
      }
      double worst = std::numeric_limits<double>::infinity();
      for (int j = 0; j <= 200; ++j)
        worst = std::min(worst, signed_distance(c, p + (s * j / 200.0) * dp, time).value + depth);
      CHECK(worst >= 0.1 * room0 - 1e-12);
    }
  CHECK(capped > 25);
}
