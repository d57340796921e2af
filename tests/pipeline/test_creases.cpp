// The creases in colour (mbi/pipeline/creases.hpp): the per-face jumps are the discontinuity
// table's energies per area, a dense point takes the jump of the faces whose band it lies in, and
// the colour scale grows hotter.
#include <catch2/catch.hpp>

#include <mbi/interp.hpp>
#include <mbi/pipeline/creases.hpp>

#include "common/grid_meshes.hpp"

#include <cmath>

using mbi::pipeline::crease_color;
using mbi::pipeline::crease_number;

TEST_CASE("creases: the face jumps are the discontinuity energies per area, a point on a face takes its jump",
          "[creases]") {
  const mbi::test::Mesh m = mbi::test::box_tet_mesh(2, 2, 2, Eigen::Vector3d(1, 1, 1));
  Eigen::MatrixXd X = m.U;
  for (Eigen::Index i = 0; i < X.rows(); ++i) X(i, 0) += 0.3 * std::sin(3 * m.U(i, 1)) * m.U(i, 2);  // a bend
  const mbi::interp::VertexMatrices Z = mbi::interp::VertexMatrices::Zero(X.size(), 3);
  const mbi::pipeline::Creases creases(m.U, m.T);
  const Eigen::VectorXd j = creases.face_jumps(X, Z);
  const Eigen::VectorXd E = mbi::interp::face_discontinuity(m.U, m.T, X, Z);
  const Eigen::MatrixXi F = mbi::interp::interior_faces(m.T);
  REQUIRE(j.size() == F.rows());
  REQUIRE(j.maxCoeff() > 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = m.U.row(F(f, 0)), b = m.U.row(F(f, 1)), c = m.U.row(F(f, 2));
    CHECK(j(f) * j(f) * 0.5 * (b - a).cross(c - a).norm() == Approx(E(f)).epsilon(1e-12).margin(1e-15));
  }
  // dense points: the centroid of face 0 (on it), and an element's centroid (away from every face)
  const int e = F(0, 3);
  Eigen::MatrixXd P(2, 3);
  P.row(0) = (m.U.row(F(0, 0)) + m.U.row(F(0, 1)) + m.U.row(F(0, 2))) / 3;
  P.row(1) = (m.U.row(m.T(e, 0)) + m.U.row(m.T(e, 1)) + m.U.row(m.T(e, 2)) + m.U.row(m.T(e, 3))) / 4;
  const mbi::interp::Embedding emb = mbi::interp::embed(m.U, m.T, P);
  const Eigen::VectorXd v = creases.point_values(emb, j);
  CHECK(v(0) >= j(0) * (1 - 1e-9));  // on face 0: at least its jump (the largest of the faces it meets)
  CHECK(v(1) == 0);                   // barycentric 1/4 > kCreaseBand from every face
  CHECK(creases.near_faces(emb) == std::vector<bool>{true, false});
}

TEST_CASE("creases: the colour scale grows hotter (red minus blue) from 0 to 1", "[creases]") {
  double last = -2;
  for (int i = 0; i <= 20; ++i) {
    const Eigen::Vector3d c = crease_color(i / 20.0);
    CHECK(c(0) - c(2) > last);
    last = c(0) - c(2);
  }
  CHECK(crease_number(0) == "0");
  CHECK(crease_number(0.33896) == "0.339");
}
