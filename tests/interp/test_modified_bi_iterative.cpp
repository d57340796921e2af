// The iterative solve path (method.md fact 19): PCG against the direct factor, its warm start,
// its adjoint against finite differences of the forward, solve_batch, and a solve that does not
// converge within its cap.
#include <catch2/catch.hpp>

#include "test_support.hpp"

#include <cmath>

using namespace mbi::interp;
using namespace mbi::test;

namespace {
struct IterFixture {
  static ModifiedBI make(const Mesh& M, SolvePath p, bool pin = false, int cap = 0) {
    Options o;
    o.solve_path = p;
    o.pin_boundary = pin;
    o.max_iterations = cap;
    return ModifiedBI(M.U, M.T, o);
  }
  static double model_size(const Mesh& M) { return (M.U.colwise().maxCoeff() - M.U.colwise().minCoeff()).norm(); }
  // largest distance between the Bezier points of two M: it bounds the distance between the
  // positions x(u) inside the control mesh (a convex combination of them)
  static double position_gap(const ModifiedBI& b, const Eigen::MatrixXd& X, const Eigen::MatrixXd& M1,
                             const Eigen::MatrixXd& M2) {
    return (b.bezier(X, M1) - b.bezier(X, M2)).rowwise().norm().maxCoeff();
  }
  static Mesh mesh(int d, int cells, unsigned seed) {
    Mesh M = d == 3 ? box_tet_mesh(cells, cells, cells) : square_tri_mesh(2 * cells, cells + 1);
    jitter(M, 0.2, 1.0 / cells, seed);
    return M;
  }
};
}  // namespace

TEST_CASE("iterative: positions within 1e-6 of the model size of the direct path, cold and warm",
          "[modified_bi][iterative]") {
  for (int d : {2, 3}) {
    for (bool pin : {false, true}) {
      const Mesh M = IterFixture::mesh(d, 6, 71);
      const ModifiedBI direct = IterFixture::make(M, SolvePath::Sparse, pin);
      const ModifiedBI iter = IterFixture::make(M, SolvePath::Iterative, pin);
      REQUIRE(iter.solve_path() == SolvePath::Iterative);
      CHECK(iter.factorization().find("PCG") != std::string::npos);
      CHECK_FALSE(iter.dense_operator());
      const double L = IterFixture::model_size(M);
      // a sequence of poses: the first from the rest pose's solution, the others warm
      int first = 0, later = 0;
      for (int k = 1; k <= 5; ++k) {
        const Eigen::MatrixXd X = smooth_deform(M.U, 0.1 * k);
        const Eigen::MatrixXd Mi = iter.solve(X);
        (k == 1 ? first : later) = std::max(k == 1 ? first : later, iter.iterations());
        CHECK(Mi.allFinite());
        CHECK(IterFixture::position_gap(iter, X, Mi, direct.solve(X)) <= 1e-6 * L);
      }
      // a fresh solver (cold: its start is the rest pose's M = 0) on the last pose
      const Eigen::MatrixXd X = smooth_deform(M.U, 0.5);
      const ModifiedBI cold = IterFixture::make(M, SolvePath::Iterative, pin);
      const Eigen::MatrixXd Mc = cold.solve(X);
      CHECK(IterFixture::position_gap(cold, X, Mc, direct.solve(X)) <= 1e-6 * L);
      INFO("d " << d << " pin " << pin << ": first " << first << ", later " << later << ", cold " << cold.iterations());
      CHECK(later < cold.iterations());  // the warm start pays
      // the same pose again: the start already meets the tolerance
      (void)cold.solve(X);
      CHECK(cold.iterations() == 0);
    }
  }
}

TEST_CASE("iterative: solve_transpose matches finite differences of the forward solve", "[modified_bi][iterative]") {
  const Mesh M = IterFixture::mesh(3, 5, 72);
  const ModifiedBI iter = IterFixture::make(M, SolvePath::Iterative);
  const ModifiedBI direct = IterFixture::make(M, SolvePath::Sparse);
  const Eigen::Index n = M.U.rows();
  const Eigen::MatrixXd X = smooth_deform(M.U, 0.3);
  const Eigen::MatrixXd G = random_matrix(3 * n, 3, 5);  // dL/dM of L = <G, M(X)>
  const Eigen::MatrixXd V = random_matrix(n, 3, 6);
  const Eigen::MatrixXd GX = iter.solve_transpose(G);
  // M is linear in X: a large step keeps the forward solve's error (1e-6 of the model size in
  // positions) small against the difference
  const double eps = 0.1;
  const double fd = ((G.array() * (iter.solve(X + eps * V) - iter.solve(X - eps * V)).array()).sum()) / (2 * eps);
  const double an = (GX.array() * V.array()).sum();
  INFO("finite difference " << fd << ", solve_transpose " << an);
  CHECK(std::abs(fd - an) <= 1e-5 * std::abs(an));
  // and the direct path's transpose to 1e-6 relative
  const Eigen::MatrixXd GXd = direct.solve_transpose(G);
  CHECK((GX - GXd).norm() <= 1e-6 * GXd.norm());
}

TEST_CASE("iterative: solve_batch and solve agree", "[modified_bi][iterative]") {
  const Mesh M = IterFixture::mesh(3, 5, 73);
  const ModifiedBI iter = IterFixture::make(M, SolvePath::Iterative);
  const Eigen::Index n = M.U.rows();
  const double L = IterFixture::model_size(M);
  Eigen::MatrixXd poses(3 * n, 3);
  for (int k = 0; k < 3; ++k) poses.middleRows(k * n, n) = smooth_deform(M.U, 0.15 * (k + 1));
  Eigen::MatrixXd Mb(3 * n * 3, 3);
  iter.solve_batch(poses, Mb);
  for (int k = 0; k < 3; ++k) {
    const Eigen::MatrixXd X = poses.middleRows(k * n, n);
    const Eigen::MatrixXd Mk = Mb.middleRows(k * n * 3, n * 3);
    CHECK(IterFixture::position_gap(iter, X, Mk, iter.solve(X)) <= 2e-6 * L);
  }
}

TEST_CASE("iterative: a solve that does not converge within its cap is an error, never NaN",
          "[modified_bi][iterative][errors]") {
  const Mesh M = IterFixture::mesh(3, 5, 74);
  const ModifiedBI capped = IterFixture::make(M, SolvePath::Iterative, false, 2);  // the rest pose needs none
  const Eigen::MatrixXd X = smooth_deform(M.U, 0.4);
  CHECK_THROWS_WITH(capped.solve(X), Catch::Contains("did not converge within 2 iterations"));
  const Eigen::MatrixXd G = random_matrix(3 * M.U.rows(), 3, 7);
  CHECK_THROWS_WITH(capped.solve_transpose(G), Catch::Contains("did not converge"));
  Eigen::MatrixXd Y = X;
  Y(3, 1) = std::nan("");
  const ModifiedBI iter = IterFixture::make(M, SolvePath::Iterative);
  CHECK_THROWS_WITH(iter.solve(Y), Catch::Contains("non-finite"));
  // after the failures the solver still solves
  CHECK(iter.solve(X).allFinite());
  CHECK(kSolvePathNames.parse("iterative", "solve_path") == SolvePath::Iterative);
}

TEST_CASE("iterative: the automatic path takes it when the factor would exceed max_memory",
          "[modified_bi][iterative][memory]") {
  const Mesh M = IterFixture::mesh(3, 11, 75);  // 1,728 vertices: above the dense operator's size
  Options o;
  o.max_memory = 1024.0 * 1024;  // below any run's estimate (the process alone counts 56 MiB)
  CHECK(ModifiedBI(M.U, M.T, o).solve_path() == SolvePath::Iterative);
  o.max_memory = 0;  // the memory there is: this mesh factors directly
  CHECK(ModifiedBI(M.U, M.T, o).solve_path() != SolvePath::Iterative);
  for (const double bad : {-1.0, std::nan(""), HUGE_VAL}) {
    o.max_memory = bad;
    CHECK_THROWS_WITH(ModifiedBI(M.U, M.T, o), Catch::Contains("max_memory"));
  }
}
