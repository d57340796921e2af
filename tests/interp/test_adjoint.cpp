// The transposes of adjoint.hpp against the forward maps: for a linear map A, <G, A x> equals
// <A^T G, x> for every x and G (to round-off), on jittered 2D and 3D meshes.
#include <catch2/catch.hpp>

#include "test_support.hpp"

#include <mbi/interp/adjoint.hpp>

#include <string>

using namespace mbi::interp;
namespace test = mbi::test;

namespace {

double dot(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) { return (A.array() * B.array()).sum(); }

// Points of the mesh: a few in every element, plus two outside (extrapolated).
Embedding points_of(const test::Mesh& m, unsigned seed) {
  std::mt19937 rng(seed);
  const int d = static_cast<int>(m.U.cols());
  Eigen::MatrixXd P(3 * m.T.rows() + 2, d);
  for (Eigen::Index e = 0; e < m.T.rows(); ++e)
    for (int k = 0; k < 3; ++k)
      P.row(3 * e + k) = test::point_of(m.U, m.T, static_cast<int>(e), test::random_bary(d, rng)).transpose();
  P.row(P.rows() - 2) = m.U.colwise().maxCoeff().array() + 0.05;
  P.row(P.rows() - 1) = m.U.colwise().minCoeff().array() - 0.03;
  return embed(m.U, m.T, P);
}

}  // namespace

TEST_CASE("adjoint: evaluate_transpose is the transpose of evaluate<double>", "[adjoint]") {
  for (int d : {2, 3}) {
    const test::Mesh m = test::jittered_mesh(d, 3);
    const Embedding emb = points_of(m, 5);
    REQUIRE_FALSE(emb.outside.empty());
    const int K = (d + 1) * (d + 2) / 2;
    const BezierPoints B = test::random_matrix(m.T.rows() * K, d, 11);
    const Eigen::MatrixXd G = test::random_matrix(emb.size(), d, 12);
    Eigen::MatrixXd positions;
    evaluate<double>(B, emb, positions);
    for (int threads : {1, 2, 3}) {
      const BezierPoints GB = evaluate_transpose(emb, G, static_cast<int>(m.T.rows()), threads);
      REQUIRE(GB.rows() == B.rows());
      REQUIRE(GB.cols() == d);
      const double lhs = dot(G, positions), rhs = dot(GB, B);
      CHECK(std::abs(lhs - rhs) <= 1e-12 * (std::abs(lhs) + G.cwiseAbs().sum()));
    }
  }
}

TEST_CASE("adjoint: evaluate_transpose reads strided G and refuses bad input", "[adjoint]") {
  const test::Mesh m = test::jittered_mesh(3, 4);
  const Embedding emb = points_of(m, 6);
  const int me = static_cast<int>(m.T.rows());
  // G row after row (a C-order numpy array), read in place through strides: the same sums
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::MatrixXd G = test::random_matrix(emb.size(), 3, 13);
  const RowMatrix Grow = G;
  const Eigen::Map<const Eigen::MatrixXd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>> Gmap(
      Grow.data(), Grow.rows(), 3, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(1, 3));
  CHECK((evaluate_transpose(emb, Gmap, me, 1) - evaluate_transpose(emb, G, me, 1)).cwiseAbs().maxCoeff() == 0.0);

  Eigen::MatrixXd bad = G;
  bad(7, 2) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(evaluate_transpose(emb, bad, me), Catch::Contains("row 7"));
  bad(7, 2) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(evaluate_transpose(emb, bad, me), Catch::Contains("row 7"));
  CHECK_THROWS_AS(evaluate_transpose(emb, G.topRows(3), me), Error);
  CHECK_THROWS_AS(evaluate_transpose(emb, G, me - 1), Error);  // a point's element is out of range
}

TEST_CASE("adjoint: bezier_transpose is the transpose of bezier_points and bezier_bi", "[adjoint]") {
  for (int d : {2, 3}) {
    const test::Mesh m = test::jittered_mesh(d, 7);
    const Eigen::Index n = m.U.rows();
    const int K = (d + 1) * (d + 2) / 2;
    const Eigen::MatrixXd X = test::random_matrix(n, d, 21);
    const VertexMatrices M = test::random_matrix(n * d, d, 22);
    const BezierPoints G = test::random_matrix(m.T.rows() * K, d, 23);
    const BezierTranspose t = bezier_transpose(m.U, m.T, G);
    const double lhs = dot(G, bezier_points(m.U, m.T, X, M));
    CHECK(std::abs(lhs - (dot(t.X, X) + dot(t.M, M))) <= 1e-12 * (1 + std::abs(lhs)) * G.size());
    const double bi = dot(G, bezier_bi(X, m.T));
    CHECK(std::abs(bi - dot(t.X, X)) <= 1e-12 * (1 + std::abs(bi)) * G.size());
  }
  const test::Mesh m = test::jittered_mesh(3, 7);
  CHECK_THROWS_AS(bezier_transpose(m.U, m.T, Eigen::MatrixXd::Zero(5, 3)), Error);
}

TEST_CASE("adjoint: ModifiedBI::solve_transpose is the transpose of solve", "[adjoint]") {
  for (int d : {2, 3})
    for (SolvePath path : {SolvePath::Sparse, SolvePath::Dense})
      for (bool pin : {false, true}) {
        INFO("d " << d << " dense " << (path == SolvePath::Dense) << " pin_boundary " << pin);
        const test::Mesh m = test::jittered_mesh(d, 9);
        const ModifiedBI solver(m.U, m.T, {.pin_boundary = pin, .solve_path = path});
        const Eigen::MatrixXd X = test::smooth_deform(m.U, 0.4) + 0.1 * test::random_matrix(m.U.rows(), d, 31);
        const VertexMatrices G = test::random_matrix(m.U.rows() * d, d, 32);
        const Eigen::MatrixXd GX = solver.solve_transpose(G);
        REQUIRE(GX.rows() == m.U.rows());
        const VertexMatrices M = solver.solve(X);
        const double lhs = dot(G, M), rhs = dot(GX, X);
        CHECK(std::abs(lhs - rhs) <= 1e-10 * (std::abs(lhs) + G.cwiseAbs().sum() * M.cwiseAbs().maxCoeff()));
      }
  const test::Mesh m = test::jittered_mesh(3, 9);
  const ModifiedBI solver(m.U, m.T);
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(m.U.rows() * 3, 3);
  G(4, 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(solver.solve_transpose(G), Catch::Contains("row 4"));
  CHECK_THROWS_AS(solver.solve_transpose(Eigen::MatrixXd::Zero(3, 3)), Error);
}

TEST_CASE("adjoint: Phong::M_transpose is the transpose of Phong::M", "[adjoint]") {
  for (int d : {2, 3}) {
    const test::Mesh m = test::jittered_mesh(d, 13);
    const Phong phong(m.U, m.T);
    const Eigen::MatrixXd X = test::smooth_deform(m.U, 0.4);
    const VertexMatrices G = test::random_matrix(m.U.rows() * d, d, 41);
    const double lhs = dot(G, phong.M(X)), rhs = dot(phong.M_transpose(G), X);
    CHECK(std::abs(lhs - rhs) <= 1e-11 * (1 + std::abs(lhs)) * G.size());
  }
  const test::Mesh m = test::jittered_mesh(2, 13);
  CHECK_THROWS_AS(Phong(m.U, m.T).M_transpose(Eigen::MatrixXd::Zero(2, 2)), Error);
}

TEST_CASE("adjoint: M at a few vertices and its transpose, through the Bezier points of a few elements",
          "[adjoint][modified_bi]") {
  for (int d : {2, 3})
    for (SolvePath path : {SolvePath::Dense, SolvePath::Sparse})
      for (bool pin : {false, true}) {
        INFO("d " << d << " dense " << (path == SolvePath::Dense) << " pin_boundary " << pin);
        const test::Mesh m = test::jittered_mesh(d, 17);
        const Eigen::Index n = m.U.rows();
        const int K = (d + 1) * (d + 2) / 2;
        const ModifiedBI solver(m.U, m.T, {.pin_boundary = pin, .solve_path = path});
        const Eigen::MatrixXd X = test::smooth_deform(m.U, 0.4) + 0.1 * test::random_matrix(n, d, 51);
        // a few elements, ascending, and their vertices listed twice and out of order
        std::vector<int> elements, vertices;
        for (int e = 1; e < m.T.rows(); e += 5) elements.push_back(e);
        for (int e : elements)
          for (int k = d; k >= 0; --k) vertices.push_back(m.T(e, k));
        const VertexMatrices full = solver.solve(X);
        VertexMatrices M = VertexMatrices::Constant(n * d, d, std::nan(""));
        solver.solve_vertices(X, vertices, M);
        for (int i : vertices)
          for (int c = 0; c < d; ++c)
            for (int r = 0; r < d; ++r) REQUIRE(M(i * d + c, r) == full(i * d + c, r));
        // the Bezier points of those elements: the full ones' rows, to the bit; the others untouched
        const BezierPoints Bfull = bezier_points(m.U, m.T, X, full);
        BezierPoints B = BezierPoints::Constant(m.T.rows() * K, d, 7.0);
        bezier_points(m.U, m.T, X, M, elements, B);
        for (int e : elements) REQUIRE(B.middleRows(e * K, K) == Bfull.middleRows(e * K, K));
        CHECK(B.row(0).isConstant(7.0));
        // the transpose: dL/dB on those elements only, the same to the bit as the full transpose,
        // then dL/dM at their vertices into dL/dX, against solve_transpose
        BezierPoints GB = BezierPoints::Zero(m.T.rows() * K, d);
        for (int e : elements) GB.middleRows(e * K, K) = test::random_matrix(K, d, 60 + static_cast<unsigned>(e));
        const BezierTranspose t = bezier_transpose(m.U, m.T, GB);
        Eigen::MatrixXd GX(n, d);
        VertexMatrices GM(n * d, d);
        bezier_transpose(m.U, m.T, GB, elements, GX, GM);
        REQUIRE(GX == t.X);
        REQUIRE(GM == t.M);
        const Eigen::MatrixXd want = solver.solve_transpose(GM);
        Eigen::MatrixXd got(n, d);
        solver.solve_transpose_vertices(GM, vertices, got);
        CHECK((got - want).cwiseAbs().maxCoeff() <= 1e-10 * (1 + want.cwiseAbs().maxCoeff()));
        const double lhs = dot(GM, full), rhs = dot(got, X);
        CHECK(std::abs(lhs - rhs) <= 1e-10 * (std::abs(lhs) + GM.cwiseAbs().sum() * full.cwiseAbs().maxCoeff()));
      }
}

TEST_CASE("adjoint: the vertex and element lists are checked", "[adjoint][modified_bi]") {
  const test::Mesh m = test::jittered_mesh(3, 17);
  const Eigen::Index n = m.U.rows();
  const ModifiedBI solver(m.U, m.T, {.solve_path = SolvePath::Dense});
  VertexMatrices M(n * 3, 3);
  const std::vector<int> bad = {0, static_cast<int>(n)};
  CHECK_THROWS_WITH(solver.solve_vertices(m.U, bad, M), Catch::Contains("vertices[1]"));
  Eigen::MatrixXd GX(n, 3);
  CHECK_THROWS_WITH(solver.solve_transpose_vertices(VertexMatrices::Zero(n * 3, 3), bad, GX),
                    Catch::Contains("vertices[1]"));
  VertexMatrices G = VertexMatrices::Zero(n * 3, 3);
  G(3, 2) = std::numeric_limits<double>::infinity();
  const std::vector<int> one = {1};
  CHECK_THROWS_WITH(solver.solve_transpose_vertices(G, one, GX), Catch::Contains("row 3"));
  BezierPoints B(m.T.rows() * 10, 3);
  const std::vector<int> elements = {-1};
  CHECK_THROWS_WITH(bezier_points(m.U, m.T, m.U, M, elements, B), Catch::Contains("elements[0]"));
  CHECK_THROWS_WITH(bezier_transpose(m.U, m.T, B, elements, GX, M), Catch::Contains("elements[0]"));
}
