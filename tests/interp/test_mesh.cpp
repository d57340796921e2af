// Mesh validation and topology (2D and 3D).
#include <mbi/interp/mesh.hpp>

#include <catch2/catch.hpp>

#include "common/grid_meshes.hpp"

#include <set>

using namespace mbi::interp;
using mbi::test::box_tet_mesh;
using mbi::test::square_tri_mesh;

TEST_CASE("volumes of the generated meshes sum to the box volume", "[mesh]") {
  auto M3 = box_tet_mesh(2, 3, 4, Eigen::Vector3d(1.0, 2.0, 3.0));
  double v = 0;
  for (int e = 0; e < M3.T.rows(); ++e) {
    const double ve = element_volume(M3.U, M3.T, e);
    CHECK(ve > 0);
    v += ve;
  }
  CHECK(v == Approx(6.0).epsilon(1e-12));  // 1 x 2 x 3 box
  auto M2 = square_tri_mesh(3, 2, Eigen::Vector2d(2.0, 0.5));
  double a = 0;
  for (int e = 0; e < M2.T.rows(); ++e) a += element_volume(M2.U, M2.T, e);
  CHECK(a == Approx(1.0).epsilon(1e-12));
}

TEST_CASE("validate_mesh names the offending element or vertex", "[mesh]") {
  auto M = box_tet_mesh(2, 2, 2);
  REQUIRE_NOTHROW(validate_mesh(M.U, M.T));
  SECTION("degenerate element") {
    auto U = M.U;
    const int e = 5;
    // Move vertex 3 of element 5 onto the plane of its other three vertices: zero volume.
    const Eigen::RowVector3d c = (U.row(M.T(e, 0)) + U.row(M.T(e, 1)) + U.row(M.T(e, 2))) / 3.0;
    auto T = M.T;
    Eigen::MatrixXd U2(U.rows() + 1, 3);
    U2 << U, c;
    T(e, 3) = static_cast<int>(U.rows());
    // the message names the element, not the library function
    CHECK_THROWS_WITH(validate_mesh(U2, T), Catch::StartsWith("element 5") && Catch::Contains("degenerate"));
  }
  SECTION("index out of range") {
    auto T = M.T;
    T(7, 2) = 1000;
    CHECK_THROWS_WITH(validate_mesh(M.U, T), Catch::Contains("element 7"));
  }
  SECTION("repeated index") {
    auto T = M.T;
    T(3, 1) = T(3, 0);
    CHECK_THROWS_WITH(validate_mesh(M.U, T), Catch::Contains("element 3") && Catch::Contains("repeats"));
  }
  SECTION("NaN vertex") {
    auto U = M.U;
    U(4, 1) = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_WITH(validate_mesh(U, M.T), Catch::Contains("vertex 4"));
  }
  SECTION("wrong shapes") {
    CHECK_THROWS_AS(validate_mesh(Eigen::MatrixXd::Zero(4, 4), M.T), Error);
    CHECK_THROWS_AS(validate_mesh(M.U, M.T.leftCols(3)), Error);
  }
  SECTION("2D degenerate triangle") {
    auto M2 = square_tri_mesh(2, 2);
    M2.U.row(M2.T(2, 2)) = 0.5 * (M2.U.row(M2.T(2, 0)) + M2.U.row(M2.T(2, 1)));
    CHECK_THROWS_WITH(validate_mesh(M2.U, M2.T), Catch::Contains("element"));
  }
}

TEST_CASE("interior and boundary faces", "[mesh]") {
  SECTION("3D box") {
    const int nx = 2, ny = 3, nz = 2;
    auto M = box_tet_mesh(nx, ny, nz);
    const Eigen::MatrixXi F = interior_faces(M.T);
    const Eigen::MatrixXi B = boundary_faces(M.U, M.T);
    // Every element has 4 faces: 4 m = 2 F + B. Boundary: 2 triangles per boundary square.
    CHECK(4 * M.T.rows() == 2 * F.rows() + B.rows());
    CHECK(B.rows() == 4 * (nx * ny + ny * nz + nx * nz));
    std::set<std::array<int, 3>> seen;
    for (int f = 0; f < F.rows(); ++f) {
      CHECK(F(f, 0) < F(f, 1));
      CHECK(F(f, 1) < F(f, 2));
      CHECK(seen.insert({F(f, 0), F(f, 1), F(f, 2)}).second);  // each face once
      for (int s : {3, 4}) {  // both elements contain the face's vertices
        int hits = 0;
        for (int k = 0; k < 4; ++k)
          for (int j = 0; j < 3; ++j) hits += M.T(F(f, s), k) == F(f, j);
        CHECK(hits == 3);
      }
    }
    // Outward orientation: the normal points away from the box centre (box is convex).
    const Eigen::RowVector3d centre(0.5, 0.5, 0.5);
    for (int b = 0; b < B.rows(); ++b) {
      const Eigen::RowVector3d a = M.U.row(B(b, 0)), p = M.U.row(B(b, 1)), q = M.U.row(B(b, 2));
      const Eigen::RowVector3d nrm = (p - a).cross(q - a);
      CHECK(nrm.dot((a + p + q) / 3.0 - centre) > 0);
    }
    const Eigen::VectorXi bv = boundary_vertices(static_cast<int>(M.U.rows()), M.T);
    CHECK(bv.sum() == (nx + 1) * (ny + 1) * (nz + 1) - (nx - 1) * (ny - 1) * (nz - 1));
  }
  SECTION("2D rectangle") {
    auto M = square_tri_mesh(3, 2);
    const Eigen::MatrixXi F = interior_faces(M.T);
    const Eigen::MatrixXi B = boundary_faces(M.U, M.T);
    CHECK(3 * M.T.rows() == 2 * F.rows() + B.rows());
    CHECK(B.rows() == 2 * (3 + 2));
    const Eigen::RowVector2d centre(0.5, 0.5);
    for (int b = 0; b < B.rows(); ++b) {
      const Eigen::RowVector2d t = M.U.row(B(b, 1)) - M.U.row(B(b, 0));
      const Eigen::RowVector2d nrm(t.y(), -t.x());
      CHECK(nrm.dot(0.5 * (M.U.row(B(b, 0)) + M.U.row(B(b, 1))) - centre) > 0);
    }
    CHECK(boundary_vertices(static_cast<int>(M.U.rows()), M.T).sum() == 12 - 2);
  }
}

TEST_CASE("basis gradients reproduce linear functions", "[mesh]") {
  for (int d : {2, 3}) {
    auto M = d == 3 ? box_tet_mesh(2, 2, 2) : square_tri_mesh(3, 3);
    mbi::test::jitter(M, 0.2, 0.5 / (d == 3 ? 1 : 1.5), 3);
    const Eigen::VectorXd g = Eigen::VectorXd::LinSpaced(d, 0.3, -1.1);
    for (int e = 0; e < M.T.rows(); ++e) {
      const Eigen::MatrixXd A = basis_gradients(M.U, M.T, e);
      // sum_i a_i = 0 (partition of unity); sum_i a_i (g . u_i) = g (linear precision). Tol 1e-12.
      CHECK(A.colwise().sum().norm() < 1e-12);
      Eigen::VectorXd r = Eigen::VectorXd::Zero(d);
      for (int k = 0; k <= d; ++k) r += A.row(k).transpose() * g.dot(M.U.row(M.T(e, k)));
      CHECK((r - g).norm() < 1e-12);
    }
  }
}
