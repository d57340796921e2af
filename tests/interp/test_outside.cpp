// Outside points: each one's distance to the mesh, the max-outside check and its sentences.
#include <mbi/interp/outside.hpp>

#include <catch2/catch.hpp>

#include "common/grid_meshes.hpp"

#include <cmath>
#include <limits>
#include <random>

using namespace mbi::interp;

namespace {
// Points around the unit box (covered exactly by the grid mesh), and their exact distances to it.
struct Around {
  Eigen::MatrixXd P;
  std::vector<double> distance;  // per row; 0 inside
};

Around around_unit_box(int d, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-0.8, 1.8);
  Around a{Eigen::MatrixXd(n, d), {}};
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < d; ++c) a.P(i, c) = uni(rng);
    a.distance.push_back((a.P.row(i) - a.P.row(i).cwiseMax(0.0).cwiseMin(1.0)).norm());
  }
  return a;
}
}  // namespace

TEST_CASE("outside points: each one's distance to the mesh, in P's units", "[embed]") {
  for (int d : {2, 3}) {
    const auto M = d == 3 ? mbi::test::box_tet_mesh(2, 3, 2) : mbi::test::square_tri_mesh(3, 4);
    const Around a = around_unit_box(d, 200, 5);
    const Embedding emb = embed(M.U, M.T, a.P);
    REQUIRE(emb.outside_distance.size() == emb.outside.size());
    for (std::size_t k = 0; k < emb.outside.size(); ++k)
      CHECK(emb.outside_distance[k] == Approx(a.distance[emb.outside[k]]).margin(1e-12));
  }
}

TEST_CASE("far_points: those beyond tolerance x the model size, the worst of them", "[embed]") {
  const auto M = mbi::test::box_tet_mesh(2, 2, 2);
  const Around a = around_unit_box(3, 300, 11);
  const Embedding emb = embed(M.U, M.T, a.P);
  const double size = (a.P.colwise().maxCoeff() - a.P.colwise().minCoeff()).norm();
  for (double tolerance : {0.0, 0.05, 0.2, 10.0}) {
    int count = 0, worst = -1;
    for (int i = 0; i < a.P.rows(); ++i)
      if (a.distance[i] > tolerance * size + 1e-12) {
        ++count;
        if (worst < 0 || a.distance[i] > a.distance[worst]) worst = i;
      }
    const FarPoints far = far_points(emb, a.P, tolerance);
    CHECK(far.count == count);
    CHECK(far.points == 300);
    CHECK(far.model_size == Approx(size));
    CHECK(far.worst == (count > 0 ? worst : -1));
    if (count > 0) CHECK(far.worst_distance == Approx(a.distance[worst]));
  }
  const FarPoints far = far_points(emb, a.P, 0.05);
  const std::string said = far_points_message(far, "--max-outside ", "c.msh");
  CHECK_THAT(said, Catch::StartsWith(std::to_string(far.count) + " of 300 points lie farther outside the control mesh "
                                     "c.msh than --max-outside 0.05 x the model size"));
  CHECK_THAT(said, Catch::Contains("the worst, point " + std::to_string(far.worst)));
  CHECK_THAT(outside_message(emb), Catch::StartsWith(std::to_string(emb.outside.size()) + " of 300 points lie outside"));
  CHECK(outside_message(embed(M.U, M.T, M.U)).empty());
}

TEST_CASE("far_points refuses a tolerance that is not a finite number >= 0, and points of another embedding", "[embed]") {
  const auto M = mbi::test::box_tet_mesh(1, 1, 1);
  const Around a = around_unit_box(3, 20, 3);
  const Embedding emb = embed(M.U, M.T, a.P);
  for (double bad : {-1e-9, std::nan(""), std::numeric_limits<double>::infinity()}) {
    CHECK_THROWS_WITH(check_max_outside(bad), Catch::StartsWith("max_outside must be a finite number >= 0"));
    CHECK_THROWS_AS(far_points(emb, a.P, bad), Error);
  }
  CHECK(check_max_outside(0.0) == 0.0);
  CHECK_THROWS_WITH(far_points(emb, a.P.topRows(10), 0.1), Catch::Contains("P has 10 rows, the embedding 20 points"));
}
