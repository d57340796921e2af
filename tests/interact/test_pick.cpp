// Picking: hits name the first triangle, its point and barycentrics; rays through shared edges
// and vertices hit (the slack); misses; bad rays and meshes are errors.
#include <catch2/catch.hpp>

#include <mbi/interact/error.hpp>
#include <mbi/interact/pick.hpp>

#include "common/tilted_grid.hpp"

#include <cmath>
#include <limits>

using namespace mbi::interact;

namespace {

using Grid = mbi::test::TiltedGrid;
using mbi::test::tilted_grid;

Ray ray_through(const Eigen::Vector3d& eye, const Eigen::Vector3d& p) { return {eye, p - eye}; }

}  // namespace

TEST_CASE("cast: the first triangle along the ray, its point and barycentrics", "[interact]") {
  // two squares facing the ray, at z = 1 and z = 2
  Eigen::MatrixXd V(8, 3);
  V << 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1, 0, 0, 2, 1, 0, 2, 1, 1, 2, 0, 1, 2;
  Eigen::MatrixXi F(4, 3);
  F << 4, 5, 6, 4, 6, 7, 0, 1, 2, 0, 2, 3;
  const Ray ray{Eigen::Vector3d(0.7, 0.2, 5), Eigen::Vector3d(0, 0, -2)};
  const std::optional<Hit> hit = cast(ray, V, F);
  REQUIRE(hit);
  CHECK(hit->face == 0);  // the nearer square (z = 2), either side facing
  CHECK(hit->t == Approx(1.5));  // in units of the direction's length
  CHECK((hit->point - Eigen::Vector3d(0.7, 0.2, 2)).norm() < 1e-12);
  Eigen::Vector3d from_bary = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) from_bary += hit->bary(k) * V.row(F(hit->face, k)).transpose();
  CHECK((from_bary - hit->point).norm() < 1e-12);
  CHECK(hit->bary.minCoeff() >= 0);
  CHECK(hit->bary.sum() == Approx(1));
  // from between the squares the far one is behind: the near one is hit
  CHECK(cast({Eigen::Vector3d(0.7, 0.2, 1.5), Eigen::Vector3d(0, 0, -1)}, V, F)->face == 2);
}

TEST_CASE("cast: misses beside the mesh, behind the origin and parallel to it", "[interact]") {
  const Grid g = tilted_grid(3);
  const Eigen::Vector3d mid = 0.5 * (g.at(0, 0) + g.at(3, 3));
  const Eigen::Vector3d normal = (g.at(3, 0) - g.at(0, 0)).cross(g.at(0, 3) - g.at(0, 0)).normalized();
  const Eigen::Vector3d eye = mid + 2 * normal;
  CHECK(cast(ray_through(eye, mid), g.V, g.F));
  CHECK_FALSE(cast(ray_through(eye, mid + 5 * (g.at(3, 0) - g.at(0, 0))), g.V, g.F));  // beside
  CHECK_FALSE(cast({eye, normal}, g.V, g.F));                                            // away
  CHECK_FALSE(cast({eye, g.at(3, 0) - g.at(0, 0)}, g.V, g.F));                           // parallel
}

TEST_CASE("cast: rays through shared vertices and edges hit (the slack), an exact cast misses some", "[interact]") {
  const int n = 8;
  const Grid g = tilted_grid(n);
  int exact_misses = 0;
  const std::vector<Eigen::Vector3d> points = g.shared_points();
  for (const Eigen::Vector3d& p : points) {
    const std::optional<Hit> hit = cast(ray_through(Grid::kEye, p), g.V, g.F);
    INFO("through " << p.transpose());
    REQUIRE(hit);
    CHECK((hit->point - p).norm() < 1e-9);
    CHECK(hit->bary.minCoeff() >= 0);  // clamped into the triangle
    CHECK(std::abs(hit->bary.sum() - 1) < 1e-12);
    exact_misses += !cast(ray_through(Grid::kEye, p), g.V, g.F, 0.0);
  }
  INFO("exact misses " << exact_misses << " of " << points.size());
  CHECK(exact_misses > 0);  // without the slack the shared edges and vertices lose clicks
}

TEST_CASE("cast: a zero or non-finite ray, an empty or malformed mesh are errors that say so", "[interact]") {
  const Grid g = tilted_grid(2);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d o(0, 0, 5);
  const auto fails = [&](const Ray& r, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const char* says) {
    CHECK_THROWS_WITH(cast(r, V, F), Catch::Contains(says));
    CHECK_THROWS_AS(cast(r, V, F), Error);
  };
  const Ray good{o, Eigen::Vector3d(0, 0, -1)};
  fails({o, Eigen::Vector3d::Zero()}, g.V, g.F, "direction is zero");
  fails({o, Eigen::Vector3d(nan, 0, -1)}, g.V, g.F, "direction is zero or not finite");
  fails({Eigen::Vector3d(inf, 0, 0), Eigen::Vector3d(0, 0, -1)}, g.V, g.F, "origin is not finite");
  fails(good, g.V, Eigen::MatrixXi(0, 3), "no triangles");
  fails(good, Eigen::MatrixXd(0, 3), Eigen::MatrixXi(0, 3), "no triangles");
  fails(good, g.V.leftCols(2), g.F, "3 columns");
  fails(good, g.V, g.F.leftCols(2), "3 columns");
  Eigen::MatrixXi bad = g.F;
  bad(1, 2) = static_cast<int>(g.V.rows());
  fails(good, g.V, bad, "outside V");
  bad(1, 2) = -1;
  fails(good, g.V, bad, "outside V");
  CHECK_THROWS_WITH(cast(good, g.V, g.F, -1e-9), Catch::Contains("slack"));
  CHECK_THROWS_WITH(cast(good, g.V, g.F, nan), Catch::Contains("slack"));
}
