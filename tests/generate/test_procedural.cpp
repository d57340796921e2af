// Built-in procedural meshes: sizes, closedness, orientation, valid control meshes.
#include <catch2/catch.hpp>

#include <mbi/interp/embed.hpp>
#include <mbi/interp/mesh.hpp>
#include <mbi/generate/procedural.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <map>

namespace {

// Signed volume enclosed by a closed triangle surface (divergence theorem).
double enclosed_volume(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  double vol = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    vol += a.dot(b.cross(c)) / 6.0;
  }
  return vol;
}

// Every undirected edge used by exactly two faces, in opposite directions (closed, oriented).
bool closed_and_oriented(const Eigen::MatrixXi& F) {
  std::map<std::pair<int, int>, int> count;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++count[{F(f, k), F(f, (k + 1) % 3)}];
  for (const auto& [e, c] : count)
    if (c != 1 || !count.count({e.second, e.first})) return false;
  return true;
}

}  // namespace

TEST_CASE("paper bar: 35-vertex control mesh and 23K-vertex surface", "[procedural]") {
  Eigen::MatrixXd U, V;
  Eigen::MatrixXi T, F;
  mbi::generate::paper_bar_control(U, T);
  CHECK(U.rows() == 35);
  CHECK(T.rows() == 72);
  REQUIRE_NOTHROW(mbi::interp::validate_mesh(U, T));
  double vol = 0;
  for (int e = 0; e < T.rows(); ++e) {
    const double v = mbi::interp::element_volume(U, T, e);
    CHECK(v > 0);
    vol += v;
  }
  CHECK(vol == Approx(6.0).epsilon(1e-12));  // the 1 x 1 x 6 bar, exactly tiled
  // conforming: every interior face shared by exactly two tets, boundary area = bar surface
  const Eigen::MatrixXi B = mbi::interp::boundary_faces(U, T);
  double area = 0;
  for (Eigen::Index f = 0; f < B.rows(); ++f) {
    const Eigen::Vector3d a = U.row(B(f, 0)), b = U.row(B(f, 1)), c = U.row(B(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  CHECK(area == Approx(2 * 1 + 4 * 6).epsilon(1e-12));

  mbi::generate::paper_bar_surface(V, F);
  CHECK(V.rows() == 23402);
  CHECK(closed_and_oriented(F));
  CHECK(enclosed_volume(V, F) == Approx(6.0).epsilon(1e-12));
  const mbi::interp::Embedding emb = mbi::interp::embed(U, T, V);
  CHECK(emb.outside.empty());
}

TEST_CASE("box tets, cylinder, bumpy sphere, 2D grid", "[procedural]") {
  Eigen::MatrixXd V;
  Eigen::MatrixXi T, F;
  mbi::generate::box_tets(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 3), Eigen::Vector3i(2, 3, 4), V, T);
  CHECK(V.rows() == 3 * 4 * 5);
  CHECK(T.rows() == 6 * 24);
  double vol = 0;
  for (int e = 0; e < T.rows(); ++e) vol += mbi::interp::element_volume(V, T, e);
  CHECK(vol == Approx(6.0).epsilon(1e-12));

  mbi::generate::cylinder_surface(0.5, 4.0, 64, 32, 6, V, F);
  CHECK(closed_and_oriented(F));
  const double pi = std::acos(-1.0);
  // inscribed 64-gon prism: area factor sin(2pi/64) * 64 / (2 pi)
  const double polygon = 0.5 * 64 * 0.25 * std::sin(2 * pi / 64);
  CHECK(enclosed_volume(V, F) == Approx(polygon * 4.0).epsilon(1e-9));

  mbi::generate::bumpy_sphere(1.0, 40, 0.05, V, F);
  CHECK(V.rows() == 6 * 40 * 40 + 2);
  CHECK(closed_and_oriented(F));
  CHECK(enclosed_volume(V, F) > 0);
  CHECK(V.rowwise().norm().maxCoeff() <= 1.05 + 1e-12);

  mbi::generate::grid_2d(4.0, 3.0, 4, 3, V, F);
  CHECK(V.rows() == 20);
  CHECK(F.rows() == 24);
  REQUIRE_NOTHROW(mbi::interp::validate_mesh(V, F));
  for (int e = 0; e < F.rows(); ++e) CHECK(mbi::interp::element_volume(V, F, e) == Approx(0.5));
}

TEST_CASE("twist_bend is a rigid rotation of each cross-section", "[procedural]") {
  Eigen::MatrixXd P(3, 3);
  P << 0.5, 0, 0, 0.5, 0, 6, 0, 0.5, 3;
  const double pi = std::acos(-1.0);
  const Eigen::MatrixXd X = mbi::generate::twist_bend(P, 0, 0, 0, 6, pi / 2, 0.0);
  CHECK((X.row(0) - P.row(0)).norm() < 1e-15);
  CHECK(X(1, 0) == Approx(0).margin(1e-15));
  CHECK(X(1, 1) == Approx(0.5));
  CHECK(X(2, 0) == Approx(-0.5 * std::sin(pi / 4)));
  CHECK(X(2, 1) == Approx(0.5 * std::cos(pi / 4)));
}
