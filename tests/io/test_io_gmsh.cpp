// Control meshes written by the real tools (tests/data/gmsh, see its README): every Gmsh
// format version and encoding, higher-order elements, parametric nodes, legacy VTK.
#include <mbi/io/io.hpp>

#include "common/temp_dir.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <cstdlib>
#include <fstream>

namespace fs = std::filesystem;
using namespace mbi::io;
using mbi::test::TempDir;

namespace {

fs::path data(const std::string& name) {
  const char* src = std::getenv("MBI_SOURCE_DIR");
  REQUIRE(src != nullptr);
  return fs::path(src) / "tests" / "data" / "gmsh" / name;
}

double volume(const ControlMesh& m) {
  double v = 0;
  for (Eigen::Index e = 0; e < m.T.rows(); ++e) {
    Eigen::Matrix3d E;
    for (int k = 0; k < 3; ++k) E.col(k) = (m.U.row(m.T(e, k + 1)) - m.U.row(m.T(e, 0))).transpose();
    v += std::abs(E.determinant()) / 6;
  }
  return v;
}

}  // namespace

TEST_CASE("Gmsh 2.2, 4.0, 4.1, ASCII and binary, from gmsh 4.8: the same box", "[io][gmsh]") {
  const ControlMesh ref = read_control_mesh(data("box-41.msh"));
  REQUIRE(ref.dim() == 3);
  REQUIRE(ref.T.rows() > 10);
  CHECK(volume(ref) == Approx(2.0).epsilon(1e-12));
  CHECK(ref.notes.empty());
  for (const char* name : {"box-22.msh", "box-22-bin.msh", "box-40.msh", "box-41-bin.msh", "box-41-param.msh"}) {
    INFO(name);
    const ControlMesh m = read_control_mesh(data(name));
    CHECK(m.dim() == 3);
    CHECK(m.T.rows() == ref.T.rows());
    CHECK(m.U.rows() == ref.U.rows());
    CHECK(volume(m) == Approx(2.0).epsilon(1e-12));
    // every node of the file, in file order: the deformed positions of the same file match
    CHECK(read_gmsh_nodes(data(name)) == [&] {
      Eigen::MatrixXd X = m.U;
      return X;
    }());
  }
  // binary and ASCII of one version: the same mesh (gmsh's ASCII has 16 digits)
  for (const auto& [a, b] : {std::pair{"box-22.msh", "box-22-bin.msh"}, {"box-41.msh", "box-41-bin.msh"},
                             {"box-41.msh", "box-41-param.msh"}}) {
    INFO(a << " vs " << b);
    const ControlMesh ma = read_gmsh(data(a)), mb = read_gmsh(data(b));
    CHECK((ma.U - mb.U).cwiseAbs().maxCoeff() < 1e-14);
    CHECK(ma.T == mb.T);
  }
}

TEST_CASE("Gmsh second-order tetrahedra: corners used, a note, mid-edge nodes kept", "[io][gmsh]") {
  const ControlMesh lin = read_gmsh(data("box-41.msh"));
  for (const char* name : {"box-22-order2.msh", "box-41-order2.msh"}) {
    INFO(name);
    const ControlMesh m = read_gmsh(data(name));
    CHECK(m.T.rows() == lin.T.rows());
    CHECK(m.U.rows() > lin.U.rows());  // the mid-edge nodes stay in the numbering
    CHECK(volume(m) == Approx(2.0).epsilon(1e-12));
    REQUIRE(m.notes.size() == 1);
    CHECK_THAT(m.notes[0], Catch::Contains("higher-order tetrahedra used by their corners"));
  }
}

TEST_CASE("Gmsh: a Physical Surface only is named as such, unknown types listed", "[io][gmsh]") {
  REQUIRE_THROWS_WITH(read_gmsh(data("surface-only.msh")),
                      Catch::Contains("no tetrahedra") && Catch::Contains("not in one plane") &&
                          Catch::Contains("surface mesh of a 3D model") && Catch::Contains("triangles (type 2)"));
  TempDir tmp("gmsh-types");
  std::ofstream(tmp / "q.msh") << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n"
                                  "0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 3 1\n1 1 2 3 4\n$EndElements\n";
  REQUIRE_THROWS_WITH(read_gmsh(tmp / "q.msh"), Catch::Contains("found 1 quadrangles (type 3)"));
}

TEST_CASE("Gmsh: nodes no element uses are kept, in file order", "[io][gmsh]") {
  TempDir tmp("gmsh-unused");
  std::ofstream(tmp / "a.msh") << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n30 0 1 0\n99 5 5 5\n10 0 0 0\n"
                                  "20 1 0 0\n40 0 0 1\n50 1 1 1\n$EndNodes\n$Elements\n2\n"
                                  "3 4 2 1 1 10 20 30 40\n4 4 2 1 1 20 30 40 50\n$EndElements\n";
  const ControlMesh m = read_gmsh(tmp / "a.msh");
  REQUIRE(m.U.rows() == 6);
  CHECK(m.U.row(1) == Eigen::RowVector3d(5, 5, 5));
  CHECK(m.T.row(0) == Eigen::RowVector4i(2, 3, 0, 4));
  CHECK(read_gmsh_nodes(tmp / "a.msh").rows() == 6);
}

TEST_CASE("legacy VTK from gmsh (ASCII, binary) and from write_vtk as control meshes", "[io][vtk]") {
  const ControlMesh a = read_control_mesh(data("box.vtk"));
  const ControlMesh b = read_control_mesh(data("box-bin.vtk"));
  REQUIRE(a.dim() == 3);
  CHECK((a.U - b.U).cwiseAbs().maxCoeff() < 1e-14);
  CHECK(a.T == b.T);
  CHECK(volume(a) == Approx(2.0).epsilon(1e-12));
  CHECK(a.T.rows() == read_gmsh(data("box-41.msh")).T.rows());
  CHECK(read_vtk_points(data("box-bin.vtk")) == b.U);
  TempDir tmp("vtk-read");
  write_vtk(tmp / "c.vtk", a.U, a.T, a.U);  // with point vectors after the cells
  const ControlMesh c = read_vtk_mesh(tmp / "c.vtk");
  CHECK(c.U == a.U);
  CHECK(c.T == a.T);
  Eigen::MatrixXd U2(4, 2);
  U2 << 0, 0, 1, 0, 1, 1, 0, 1;
  Eigen::MatrixXi T2(2, 3);
  T2 << 0, 1, 2, 0, 2, 3;
  write_vtk(tmp / "d.vtk", U2, T2);
  const ControlMesh d = read_vtk_mesh(tmp / "d.vtk");
  CHECK(d.dim() == 2);
  CHECK(d.U == U2);
  CHECK(d.T == T2);
}
