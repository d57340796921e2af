// Loop subdivision (dense.subdivide): the first vertices keep their index, a vertex no face uses
// keeps its position exactly (OpenMesh leaves it uninitialised), every position is finite.
#include <catch2/catch.hpp>

#include <mbi/generate/procedural.hpp>
#include <mbi/generate/subdivide.hpp>
#include <mbi/io/io.hpp>

#include "common/skip.hpp"

#include <set>
#include <utility>

using mbi::io::SurfaceMesh;

namespace {

// Vertices that no face of m uses.
std::set<Eigen::Index> unused(const SurfaceMesh& m) {
  std::set<Eigen::Index> out;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) out.insert(i);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) out.erase(m.F(f, k));
  return out;
}

}  // namespace

TEST_CASE("Loop subdivision keeps a vertex no face uses where it was", "[subdivide]") {
  SurfaceMesh m;
  mbi::generate::box_surface(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 3), Eigen::Vector3i(2, 2, 2), m.V, m.F);
  const Eigen::Index n = m.V.rows();
  m.V.conservativeResize(n + 2, Eigen::NoChange);  // two stray points, one of them far out
  m.V.row(n) << 0.5, 0.5, 0.5;
  m.V.row(n + 1) << -7.25, 1e3, 0.1;
  const SurfaceMesh rest = m;
  for (int steps : {1, 2}) {
    INFO(steps << " steps");
    SurfaceMesh s = rest;
    mbi::generate::loop_subdivide(s, steps);
    CHECK(s.V.rows() > rest.V.rows());
    CHECK(s.V.allFinite());
    CHECK(s.V.row(n) == rest.V.row(n));
    CHECK(s.V.row(n + 1) == rest.V.row(n + 1));
    CHECK(unused(s) == std::set<Eigen::Index>{n, n + 1});  // still unused, same index
  }
}

TEST_CASE("Loop subdivision of the Stanford bunny (1,113 unused vertices)", "[subdivide][models]") {
  SurfaceMesh m = mbi::io::read_surface(mbi::test::models_dir_or_skip() / "stanford-bunny.obj");
  const std::set<Eigen::Index> stray = unused(m);
  REQUIRE(stray.size() == 1113);
  const SurfaceMesh rest = m;
  mbi::generate::loop_subdivide(m, 1);
  CHECK(m.V.allFinite());
  for (const Eigen::Index i : stray) CHECK(m.V.row(i) == rest.V.row(i));
}
