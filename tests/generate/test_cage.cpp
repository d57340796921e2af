// Control-mesh generation: containment, topology, quality, vertex target, determinism.
#include "common/skip.hpp"
#include <mbi/interp/embed.hpp>
#include <mbi/interp/mesh.hpp>
#include <mbi/generate/cage.hpp>
#include <mbi/io/io.hpp>

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

using namespace mbi::generate;
using namespace mbi::io;

namespace {

struct Surf {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
};

/// Closed parametric surface on an (nu x nv) grid, periodic in u; poles collapse if `sphere`.
template <typename Fn>
Surf torus_like(int nu, int nv, Fn&& f) {
  Surf s;
  s.V.resize(nu * nv, 3);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) s.V.row(i * nv + j) = f(2 * M_PI * i / nu, 2 * M_PI * j / nv);
  s.F.resize(2 * nu * nv, 3);
  int r = 0;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                d = i * nv + (j + 1) % nv;
      s.F.row(r++) << a, b, c;
      s.F.row(r++) << a, c, d;
    }
  return s;
}

Surf sphere(double radius) {
  // UV sphere: rings of latitude (poles as single vertices).
  const int nu = 32, nv = 16;
  Surf s;
  s.V.resize(2 + nu * (nv - 1), 3);
  s.V.row(0) << 0, 0, radius;
  s.V.row(1) << 0, 0, -radius;
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
      s.V.row(2 + (j - 1) * nu + i) << radius * std::sin(th) * std::cos(ph),
          radius * std::sin(th) * std::sin(ph), radius * std::cos(th);
    }
  std::vector<Eigen::RowVector3i> f;
  auto id = [&](int j, int i) { return 2 + (j - 1) * nu + (i % nu); };
  for (int i = 0; i < nu; ++i) {
    f.emplace_back(0, id(1, i), id(1, i + 1));
    f.emplace_back(1, id(nv - 1, i + 1), id(nv - 1, i));
    for (int j = 1; j + 1 < nv; ++j) {
      f.emplace_back(id(j, i), id(j + 1, i), id(j + 1, i + 1));
      f.emplace_back(id(j, i), id(j + 1, i + 1), id(j, i + 1));
    }
  }
  s.F.resize(static_cast<int>(f.size()), 3);
  for (std::size_t k = 0; k < f.size(); ++k) s.F.row(static_cast<int>(k)) = f[k];
  return s;
}

/// Closed box surface [lo, hi], each face split into k x k quads (2 triangles each).
void add_box(Surf& s, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int k) {
  std::vector<Eigen::RowVector3d> V;
  std::vector<Eigen::RowVector3i> F;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      const int base = static_cast<int>(s.V.rows() + V.size());
      for (int a = 0; a <= k; ++a)
        for (int b = 0; b <= k; ++b) {
          Eigen::Vector3d p;
          p(axis) = side ? hi(axis) : lo(axis);
          p(u) = lo(u) + (hi(u) - lo(u)) * a / k;
          p(w) = lo(w) + (hi(w) - lo(w)) * b / k;
          V.emplace_back(p.transpose());
        }
      for (int a = 0; a < k; ++a)
        for (int b = 0; b < k; ++b) {
          const int p0 = base + a * (k + 1) + b, p1 = p0 + (k + 1), p2 = p1 + 1, p3 = p0 + 1;
          F.emplace_back(p0, p1, p2);
          F.emplace_back(p0, p2, p3);
        }
    }
  const Eigen::Index n0 = s.V.rows(), f0 = s.F.rows();
  s.V.conservativeResize(n0 + static_cast<Eigen::Index>(V.size()), 3);
  s.F.conservativeResize(f0 + static_cast<Eigen::Index>(F.size()), 3);
  for (std::size_t i = 0; i < V.size(); ++i) s.V.row(n0 + static_cast<Eigen::Index>(i)) = V[i];
  for (std::size_t i = 0; i < F.size(); ++i) s.F.row(f0 + static_cast<Eigen::Index>(i)) = F[i];
}

bool inside_cage(const CageResult& c, const Eigen::RowVectorXd& p) {
  const Eigen::MatrixXd P = p.leftCols(c.dim());
  return mbi::interp::embed(c.U, c.T, P).outside.empty();
}

/// Smallest angle (degrees) computed here, independently of min_dihedral_angle_deg: 3D from the
/// outward face normals (dihedral angle = pi - angle between the normals of the two faces at an
/// edge), 2D from atan2(|cross|, dot) at each corner.
double smallest_angle_deg(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T) {
  double best = 180.0;
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    if (U.cols() == 2) {
      for (int a = 0; a < 3; ++a) {
        const Eigen::Vector2d p = U.row(T(e, a)).transpose();
        const Eigen::Vector2d u = U.row(T(e, (a + 1) % 3)).transpose() - p;
        const Eigen::Vector2d w = U.row(T(e, (a + 2) % 3)).transpose() - p;
        best = std::min(best, std::atan2(std::abs(u.x() * w.y() - u.y() * w.x()), u.dot(w)) * 180 / M_PI);
      }
      continue;
    }
    Eigen::Vector3d n[4];  // n[k]: outward unit normal of the face opposite vertex k
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d a = U.row(T(e, (k + 1) % 4)).transpose(), b = U.row(T(e, (k + 2) % 4)).transpose(),
                            c = U.row(T(e, (k + 3) % 4)).transpose(), o = U.row(T(e, k)).transpose();
      n[k] = (b - a).cross(c - a).normalized();
      if (n[k].dot(o - a) > 0) n[k] = -n[k];
    }
    for (int k = 0; k < 4; ++k)
      for (int l = k + 1; l < 4; ++l)
        best = std::min(best, 180.0 - std::acos(std::clamp(n[k].dot(n[l]), -1.0, 1.0)) * 180 / M_PI);
  }
  return best;
}

/// Voxel cages: every element spans exactly one grid cell (its bounding box), and all cells are
/// the same; returns the cell's edge lengths (d of them).
Eigen::VectorXd voxel_cell(const CageResult& c) {
  const int d = c.dim();
  Eigen::VectorXd cell(d);
  for (Eigen::Index e = 0; e < c.T.rows(); ++e) {
    Eigen::VectorXd lo = c.U.row(c.T(e, 0)).transpose(), hi = lo;
    for (int k = 1; k <= d; ++k) {
      lo = lo.cwiseMin(c.U.row(c.T(e, k)).transpose());
      hi = hi.cwiseMax(c.U.row(c.T(e, k)).transpose());
    }
    if (e == 0) cell = hi - lo;
    REQUIRE((hi - lo - cell).cwiseAbs().maxCoeff() <= 1e-9 * cell.maxCoeff());
  }
  return cell;
}

/// The properties every cage must have, checked independently of the generator's own report,
/// with the bounds that cage.hpp and docs/cli.md promise:
///   voxel:  vertex count within 10% of the target (the cell size search prefers such counts);
///           smallest dihedral angle >= 45 deg with cubic cells, >= 30 deg otherwise, where the
///           cell aspect ratio is at most 1.6 (2D: smallest triangle angle, same bounds);
///   TetGen: vertex count within 30% of the target, smallest dihedral angle >= 5 deg.
void check_cage(const Surf& s, const CageResult& c, int target) {
  const double angle = smallest_angle_deg(c.U, c.T);
  INFO("target " << target << ": " << c.U.rows() << " vertices, " << c.T.rows()
                 << " elements, min angle " << c.min_dihedral_deg << " (here " << angle << "), h "
                 << c.cell_size << ", mesher " << mesher_name(c.mesher));
  REQUIRE(c.T.cols() == c.dim() + 1);
  REQUIRE_NOTHROW(mbi::interp::validate_mesh(c.U, c.T));
  for (Eigen::Index e = 0; e < c.T.rows(); ++e)
    REQUIRE(mbi::interp::element_volume(c.U, c.T, static_cast<int>(e)) > 0);
  const Eigen::MatrixXd P = s.V.leftCols(c.dim());
  const auto emb = mbi::interp::embed(c.U, c.T, P);
  REQUIRE(emb.outside.empty());
  REQUIRE(c.outside_points == 0);
  REQUIRE(c.min_dihedral_deg == Approx(min_dihedral_angle_deg(c.U, c.T)));
  REQUIRE(angle == Approx(c.min_dihedral_deg).epsilon(1e-9));
  if (c.mesher == Mesher::Voxel) {
    CHECK(std::abs(c.U.rows() - target) <= 0.1 * target);
    const Eigen::VectorXd cell = voxel_cell(c);
    const double aspect = cell.maxCoeff() / cell.minCoeff();
    INFO("cell aspect ratio " << aspect);
    REQUIRE(c.cell_size == Approx(cell.maxCoeff()).epsilon(1e-9));
    if (aspect <= 1 + 1e-9) {
      CHECK(angle >= 45.0 - 1e-9);
    } else {
      CHECK(aspect <= 1.6 + 1e-9);
      CHECK(angle >= 30.0);
    }
  } else {
    CHECK(std::abs(c.U.rows() - target) <= 0.3 * target);
    CHECK(angle >= 5.0);
  }
  // Every control vertex is used by an element.
  Eigen::VectorXi used = Eigen::VectorXi::Zero(c.U.rows());
  for (Eigen::Index i = 0; i < c.T.size(); ++i) used(c.T.data()[i]) = 1;
  REQUIRE(used.minCoeff() == 1);
}

void check_deterministic(const Surf& s, const CageOptions& opt, const CageResult& first) {
  const CageResult again = make_cage(s.V, s.F, opt);
  REQUIRE(again.U.rows() == first.U.rows());
  REQUIRE((again.U.array() == first.U.array()).all());
  REQUIRE(again.T == first.T);
}

}  // namespace

TEST_CASE("min_dihedral_angle_deg on tetrahedra with known angles", "[cage]") {
  Eigen::MatrixXd U(4, 3);
  U << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1;  // regular
  Eigen::MatrixXi T(1, 4);
  T << 0, 1, 2, 3;
  REQUIRE(min_dihedral_angle_deg(U, T) == Approx(std::acos(1.0 / 3.0) * 180 / M_PI).epsilon(1e-12));
  U << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;  // corner: 90 at the origin, acos(1/sqrt 3) elsewhere
  REQUIRE(min_dihedral_angle_deg(U, T) ==
          Approx(std::acos(1.0 / std::sqrt(3.0)) * 180 / M_PI).epsilon(1e-12));
  Eigen::MatrixXd U2(3, 2);
  U2 << 0, 0, 2, 0, 0, 1;
  Eigen::MatrixXi T2(1, 3);
  T2 << 0, 1, 2;
  REQUIRE(min_dihedral_angle_deg(U2, T2) == Approx(std::atan(0.5) * 180 / M_PI).epsilon(1e-12));
}

TEST_CASE("cage of a sphere", "[cage]") {
  const Surf s = sphere(1.3);
  for (int target : {40, 150, 450}) {
    CageOptions opt;
    opt.target_vertices = target;
    const CageResult c = make_cage(s.V, s.F, opt);
    check_cage(s, c, target);
    REQUIRE(c.dim() == 3);
    if (target == 150) check_deterministic(s, opt, c);
  }
}

TEST_CASE("cage of an open surface (sphere with a hole) and of a point cloud", "[cage]") {
  Surf s = sphere(1.0);
  // Remove the faces around the north pole: the surface is no longer closed.
  Eigen::MatrixXi kept(s.F.rows(), 3);
  int k = 0;
  for (Eigen::Index f = 0; f < s.F.rows(); ++f) {
    double z = 0;
    for (int c = 0; c < 3; ++c) z += s.V(s.F(f, c), 2) / 3;
    if (z < 0.6) kept.row(k++) = s.F.row(f);
  }
  REQUIRE(k < s.F.rows());
  s.F = kept.topRows(k);
  CageOptions opt;
  opt.target_vertices = 200;
  check_cage(s, make_cage(s.V, s.F, opt), 200);
  const Surf cloud{s.V, Eigen::MatrixXi(0, 3)};
  check_cage(cloud, make_cage(cloud.V, cloud.F, opt), 200);
}

TEST_CASE("cage of a torus keeps the hole open", "[cage]") {
  const Surf s = torus_like(48, 16, [](double u, double v) {
    const double R = 2.0, r = 0.5;
    return Eigen::RowVector3d((R + r * std::cos(v)) * std::cos(u),
                              (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
  });
  CageOptions opt;
  opt.target_vertices = 300;
  const CageResult c = make_cage(s.V, s.F, opt);
  check_cage(s, c, 300);
  REQUIRE_FALSE(inside_cage(c, Eigen::RowVector3d(0, 0, 0)));     // centre of the hole
  REQUIRE_FALSE(inside_cage(c, Eigen::RowVector3d(0.8, 0.8, 0)));  // still inside the hole
  REQUIRE(inside_cage(c, Eigen::RowVector3d(2.0, 0, 0)));          // inside the tube
  check_deterministic(s, opt, c);
}

TEST_CASE("cage of a U shape keeps the legs apart", "[cage]") {
  Surf s;
  s.V.resize(0, 3);
  s.F.resize(0, 3);
  add_box(s, {0, 0, 0}, {1, 4, 1}, 4);   // left leg
  add_box(s, {3, 0, 0}, {4, 4, 1}, 4);   // right leg
  add_box(s, {0, -1, 0}, {4, 0, 1}, 4);  // base joining them
  for (int target : {120, 250}) {
    CageOptions opt;
    opt.target_vertices = target;
    const CageResult c = make_cage(s.V, s.F, opt);
    check_cage(s, c, target);
    for (double y : {1.5, 2.5, 3.5}) {
      INFO("gap point y = " << y);
      REQUIRE_FALSE(inside_cage(c, Eigen::RowVector3d(2.0, y, 0.5)));
    }
    REQUIRE(inside_cage(c, Eigen::RowVector3d(0.5, 2.5, 0.5)));
    REQUIRE(inside_cage(c, Eigen::RowVector3d(3.5, 2.5, 0.5)));
  }
}

TEST_CASE("planar input gives a 2D triangle cage, force_3d gives tetrahedra", "[cage]") {
  // An annulus in the plane z = 0.5.
  const int nu = 40, nr = 4;
  Surf s;
  s.V.resize(nu * (nr + 1), 3);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j <= nr; ++j) {
      const double a = 2 * M_PI * i / nu, r = 1.0 + 0.1 * j;
      s.V.row(i * (nr + 1) + j) << r * std::cos(a), r * std::sin(a), 0.5;
    }
  s.F.resize(2 * nu * nr, 3);
  int k = 0;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nr; ++j) {
      const int a = i * (nr + 1) + j, b = ((i + 1) % nu) * (nr + 1) + j;
      s.F.row(k++) << a, b, b + 1;
      s.F.row(k++) << a, b + 1, a + 1;
    }
  CageOptions opt;
  opt.target_vertices = 120;
  const CageResult c = make_cage(s.V, s.F, opt);
  REQUIRE(c.dim() == 2);
  check_cage(s, c, 120);
  REQUIRE_FALSE(inside_cage(c, Eigen::RowVector2d(0, 0)));
  opt.force_3d = true;
  const CageResult c3 = make_cage(s.V, s.F, opt);
  REQUIRE(c3.dim() == 3);
  check_cage(s, c3, 120);
}

TEST_CASE("mesher names", "[cage]") {
  REQUIRE(std::string(mesher_name(Mesher::Voxel)) == "voxel");
  REQUIRE(std::string(mesher_name(Mesher::TetGen)) == "tetgen");
  REQUIRE(parse_mesher("tetgen") == Mesher::TetGen);
  REQUIRE(parse_mesher("voxel") == Mesher::Voxel);
  REQUIRE_THROWS_AS(parse_mesher("delaunay"), mbi::generate::Error);
  REQUIRE(CageOptions{}.mesher == Mesher::Voxel);
}

TEST_CASE("TetGen cage of a sphere", "[cage][tetgen]") {
  const Surf s = sphere(1.3);
  for (int target : {60, 200}) {
    CageOptions opt;
    opt.target_vertices = target;
    opt.mesher = Mesher::TetGen;
    const CageResult c = make_cage(s.V, s.F, opt);
    check_cage(s, c, target);
    REQUIRE(c.dim() == 3);
    REQUIRE(c.mesher == Mesher::TetGen);
    REQUIRE_FALSE(c.tetgen_switches.empty());
    if (target == 200) check_deterministic(s, opt, c);
  }
}

TEST_CASE("TetGen cage of a U shape keeps the legs apart", "[cage][tetgen]") {
  Surf s;
  s.V.resize(0, 3);
  s.F.resize(0, 3);
  add_box(s, {0, 0, 0}, {1, 4, 1}, 4);
  add_box(s, {3, 0, 0}, {4, 4, 1}, 4);
  add_box(s, {0, -1, 0}, {4, 0, 1}, 4);
  CageOptions opt;
  opt.target_vertices = 150;
  opt.mesher = Mesher::TetGen;
  const CageResult c = make_cage(s.V, s.F, opt);
  check_cage(s, c, 150);
  for (double y : {1.5, 2.5, 3.5}) {
    INFO("gap point y = " << y);
    REQUIRE_FALSE(inside_cage(c, Eigen::RowVector3d(2.0, y, 0.5)));
  }
  REQUIRE(inside_cage(c, Eigen::RowVector3d(0.5, 2.5, 0.5)));
  REQUIRE(inside_cage(c, Eigen::RowVector3d(3.5, 2.5, 0.5)));
  check_deterministic(s, opt, c);
}

TEST_CASE("make_cage rejects bad input", "[cage]") {
  const Surf s = sphere(1.0);
  CageOptions opt;
  Eigen::MatrixXd V = s.V;
  V(3, 1) = std::nan("");
  REQUIRE_THROWS_AS(make_cage(V, s.F, opt), mbi::generate::Error);
  Eigen::MatrixXi F = s.F;
  F(2, 2) = static_cast<int>(s.V.rows());
  REQUIRE_THROWS_AS(make_cage(s.V, F, opt), mbi::generate::Error);
  opt.target_vertices = 3;
  REQUIRE_THROWS_AS(make_cage(s.V, s.F, opt), mbi::generate::Error);
  opt.target_vertices = 100;
  REQUIRE_THROWS_AS(make_cage(Eigen::MatrixXd(0, 3), Eigen::MatrixXi(0, 3), opt),
                    mbi::generate::Error);
}

TEST_CASE("cages of the real models", "[cage][models]") {
  const std::string dir = mbi::test::models_dir_or_skip().string();
  struct Job {
    const char* name;
    int target;
  };
  const Job jobs[] = {{"stanford-bunny", 100}, {"stanford-bunny", 450}, {"spot", 450},
                      {"fandisk", 450}, {"alligator", 450}, {"woody", 450}};
  auto path = [&](const Job& j) { return std::filesystem::path(dir) / (std::string(j.name) + ".obj"); };
  // every model or none: a partial set would pass having checked less than it says
  for (const Job& j : jobs)
    if (!std::filesystem::exists(path(j))) mbi::test::skip((path(j).string() + " is missing").c_str());
  for (const Job& j : jobs) {
    INFO(j.name << " target " << j.target);
    const SurfaceMesh m = read_surface(path(j));
    Surf s{m.V, m.F};
    CageOptions opt;
    opt.target_vertices = j.target;
    const CageResult c = make_cage(s.V, s.F, opt);
    check_cage(s, c, j.target);
    if (j.target == 450 && std::string(j.name) == "stanford-bunny") check_deterministic(s, opt, c);
  }
}

TEST_CASE("TetGen cages of the bunny", "[cage][models][tetgen]") {
  const std::string dir = mbi::test::models_dir_or_skip().string();
  const std::filesystem::path p = std::filesystem::path(dir) / "stanford-bunny.obj";
  if (!std::filesystem::exists(p)) mbi::test::skip((p.string() + " is missing").c_str());
  const SurfaceMesh m = read_surface(p);
  const Surf s{m.V, m.F};
  for (int target : {100, 450}) {
    CageOptions opt;
    opt.target_vertices = target;
    opt.mesher = Mesher::TetGen;
    const CageResult c = make_cage(s.V, s.F, opt);
    check_cage(s, c, target);
    REQUIRE(c.mesher == Mesher::TetGen);
    if (target == 100) check_deterministic(s, opt, c);
  }
}

TEST_CASE("is_planar: a model with one z and some extent in x or y", "[cage]") {
  Eigen::MatrixXd V(4, 3);
  V << 0, 0, 2, 1, 0, 2, 0, 1, 2, 1, 1, 2;
  CHECK(mbi::generate::is_planar(V));
  Eigen::MatrixXd line = V;
  line.col(1).setZero();  // still a line in the plane: planar
  CHECK(mbi::generate::is_planar(line));
  Eigen::MatrixXd bent = V;
  bent(3, 2) = 2.0000001;
  CHECK_FALSE(mbi::generate::is_planar(bent));
  CHECK_FALSE(mbi::generate::is_planar(V.topRows(1)));                        // one point: degenerate
  CHECK_FALSE(mbi::generate::is_planar(Eigen::MatrixXd::Constant(5, 3, 1.5)));  // all equal: degenerate
  Eigen::MatrixXd nan = V;
  nan(0, 0) = std::nan("");
  CHECK_FALSE(mbi::generate::is_planar(nan));
  CHECK_FALSE(mbi::generate::is_planar(V.leftCols(2)));  // 2 columns: already 2D, not a flat 3D model
  CHECK_FALSE(mbi::generate::is_planar(Eigen::MatrixXd(0, 3)));
}
