// Precompute, the one dispatch on the method: each method's M and Bezier points against interp's
// own calls, methods built on demand, alpha checked and applied by interp, bad poses refused.
#include <catch2/catch.hpp>

#include <mbi/interp.hpp>
#include <mbi/pipeline/precompute.hpp>

#include "common/grid_meshes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

using namespace mbi;
using pipeline::Method;
using pipeline::Precompute;

namespace {

test::Mesh mesh(int d) {
  test::Mesh m = d == 3 ? test::box_tet_mesh(3, 2, 2, Eigen::Vector3d(2, 1, 1)) : test::square_tri_mesh(4, 3);
  test::jitter(m, 0.15, d == 3 ? 0.5 : 0.2, 5);
  return m;
}

// A smooth bend and shear of the rest positions.
Eigen::MatrixXd pose(const Eigen::MatrixXd& U) {
  Eigen::MatrixXd X = U;
  for (Eigen::Index i = 0; i < U.rows(); ++i) {
    X(i, 1) += 0.3 * U(i, 0) * U(i, 0);
    X(i, 0) += 0.2 * U(i, 1);
  }
  return X;
}

}  // namespace

TEST_CASE("Precompute: every method's M and Bezier points are interp's", "[precompute]") {
  for (int d : {2, 3}) {
    CAPTURE(d);
    const test::Mesh m = mesh(d);
    const Eigen::MatrixXd X = pose(m.U);
    Precompute pre(m.U, m.T, Method::BI);
    CHECK(pre.built_solver() == nullptr);
    CHECK(pre.built_phong() == nullptr);

    const interp::ModifiedBI mbi(m.U, m.T);
    const interp::VertexMatrices M = pre.M(Method::ModifiedBI, X);  // builds the solver now
    REQUIRE(pre.built_solver() != nullptr);
    CHECK(pre.precompute_ms() > 0);
    CHECK((M - mbi.solve(X)).cwiseAbs().maxCoeff() < 1e-12);
    CHECK((pre.bezier(Method::ModifiedBI, X) - mbi.bezier(X, mbi.solve(X))).cwiseAbs().maxCoeff() < 1e-12);

    const interp::Phong phong(m.U, m.T);
    CHECK((pre.M(Method::Phong, X) - phong.M(X)).cwiseAbs().maxCoeff() == 0);
    CHECK(pre.built_phong() != nullptr);

    CHECK(pre.M(Method::BI, X).isZero(0));
    CHECK(pre.bezier(Method::BI, X) == interp::bezier_bi(X, m.T));
  }
}

TEST_CASE("Precompute: the method named at construction is built, the others wait", "[precompute]") {
  const test::Mesh m = mesh(3);
  const Precompute phong_only(m.U, m.T, Method::Phong);
  CHECK(phong_only.built_phong() != nullptr);
  CHECK(phong_only.built_solver() == nullptr);
  // the const call does not build: it refuses a method that is not there
  CHECK_THROWS_WITH(phong_only.M(Method::ModifiedBI, m.U), Catch::Contains("not built"));
}

TEST_CASE("Precompute: alpha's default, check and change come from interp", "[precompute]") {
  const test::Mesh m = mesh(3);
  Precompute pre(m.U, m.T, Method::ModifiedBI);
  CHECK(pre.built_solver()->alpha() == interp::default_alpha(3));
  pre.set_alpha(0.4);
  CHECK(pre.built_solver()->alpha() == 0.4);
  const interp::ModifiedBI ref(m.U, m.T, {.alpha = 0.4});
  const Eigen::MatrixXd X = pose(m.U);
  CHECK((pre.M(Method::ModifiedBI, X) - ref.solve(X)).cwiseAbs().maxCoeff() < 1e-12);
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()}) {
    CHECK_THROWS_WITH(pre.set_alpha(bad), Catch::Contains("alpha must be"));
    CHECK(pre.built_solver()->alpha() == 0.4);  // unchanged after a refused value
  }
  // refused before the solver exists too, and at construction
  Precompute lazy(m.U, m.T, Method::BI);
  CHECK_THROWS_WITH(lazy.set_alpha(-2.0), Catch::Contains("alpha must be"));
  CHECK_THROWS_WITH(Precompute(m.U, m.T, Method::BI, {.alpha = -1.0}), Catch::Contains("alpha must be"));
}

TEST_CASE("Precompute: poses of the wrong shape or with NaN are refused for every method", "[precompute]") {
  const test::Mesh m = mesh(2);
  Precompute pre(m.U, m.T, Method::ModifiedBI);
  pre.phong();
  Eigen::MatrixXd X = m.U;
  X(2, 1) = std::numeric_limits<double>::quiet_NaN();
  for (Method method : pipeline::all_methods()) {
    CHECK_THROWS_WITH(pre.bezier(method, X), Catch::Contains("control vertex 2"));
    CHECK_THROWS_WITH(pre.bezier(method, m.U.topRows(3)), Catch::Contains("X must be"));
  }
}

TEST_CASE("Precompute: M_transpose is the transpose of M for every method", "[precompute]") {
  const test::Mesh m = mesh(3);
  Precompute pre(m.U, m.T, Method::ModifiedBI);
  pre.phong();
  const Eigen::MatrixXd X = pose(m.U);
  // <G, M(X)> = <M_transpose(G), X> for the linear maps X -> M
  const Eigen::MatrixXd G = Eigen::MatrixXd::NullaryExpr(
      m.U.rows() * 3, 3, [](Eigen::Index i, Eigen::Index j) { return std::sin(1.0 + double(i) + 3.0 * double(j)); });
  for (Method method : pipeline::all_methods()) {
    CAPTURE(pipeline::method_name(method));
    const double lhs = (G.array() * pre.M(method, X).array()).sum();
    const double rhs = (pre.M_transpose(method, G).array() * X.array()).sum();
    CHECK(std::abs(lhs - rhs) <= 1e-9 * std::max(1.0, std::abs(lhs)));
  }
}
