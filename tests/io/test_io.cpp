// Mesh IO: exact round trips of every format and clear errors on malformed files.
#include "common/skip.hpp"
#include <mbi/io/io.hpp>

#include <catch2/catch.hpp>

#include "common/files.hpp"
#include "common/temp_dir.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>

namespace fs = std::filesystem;
using namespace mbi::io;
using mbi::test::slurp;
using mbi::test::TempDir;
using mbi::test::write_text;

namespace {

/// Doubles that need all 17 digits, of varied magnitudes and signs.
double awkward(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> e(-30, 30);
  return u(rng) * std::pow(10.0, e(rng)) / 3.0;
}

/// Two components, a quad and a pentagon, three triangles on one edge (non-manifold), an
/// unreferenced vertex and a duplicated position.
SurfaceMesh awkward_mesh(bool float_values) {
  std::mt19937_64 rng(7);
  SurfaceMesh m;
  m.V.resize(12, 3);
  for (int i = 0; i < 12; ++i)
    for (int c = 0; c < 3; ++c) {
      const double x = awkward(rng);
      m.V(i, c) = float_values ? static_cast<double>(static_cast<float>(x)) : x;
    }
  m.V.row(9) = m.V.row(2);  // duplicate position
  m.polygons = {{0, 1, 2}, {0, 1, 3}, {1, 0, 4},  // three faces on edge (0,1): non-manifold
                {2, 3, 4, 5},                       // quad
                {6, 7, 8, 11, 7},                   // pentagon (second component)
                {9, 5, 4}};                         // uses the duplicate; vertex 10 unused
  int t = 0;
  for (const auto& p : m.polygons) t += static_cast<int>(p.size()) - 2;
  m.F.resize(t, 3);
  int r = 0;
  for (const auto& p : m.polygons)
    for (std::size_t k = 1; k + 1 < p.size(); ++k) m.F.row(r++) << p[0], p[k], p[k + 1];
  return m;
}

void require_same(const SurfaceMesh& a, const SurfaceMesh& b) {
  REQUIRE(a.V.rows() == b.V.rows());
  REQUIRE(a.V.cols() == b.V.cols());
  for (Eigen::Index i = 0; i < a.V.rows(); ++i)
    for (int c = 0; c < 3; ++c) REQUIRE(a.V(i, c) == b.V(i, c));  // bit-exact
  REQUIRE(a.F == b.F);
}

/// Expects an mbi::io::Error whose message starts with the file name (and ":<line>:" when line > 0)
/// and contains `what`.
template <typename F>
void require_io_error(F&& f, const fs::path& file, int line, const std::string& what) {
  try {
    f();
    FAIL("no mbi::io::Error for " << file << " (expected: " << what << ")");
  } catch (const mbi::io::Error& e) {
    const std::string msg = e.what();
    INFO(msg);
    const std::string prefix = file.string() + (line > 0 ? ":" + std::to_string(line) + ":" : ":");
    CHECK(msg.rfind(prefix, 0) == 0);
    CHECK(msg.find(what) != std::string::npos);
  }
}

}  // namespace

TEST_CASE("surface formats round-trip exactly, keeping vertex order and odd topology", "[io]") {
  TempDir tmp("surface");
  const SurfaceMesh m = awkward_mesh(false);
  for (const char* name : {"m.obj", "m.off", "m.ply"}) {
    for (Encoding enc : {Encoding::ascii, Encoding::binary}) {
      INFO(name << (enc == Encoding::binary ? " binary" : " ascii"));
      write_surface(tmp / name, m, enc);
      const SurfaceMesh r = read_surface(tmp / name);
      require_same(m, r);
      REQUIRE(r.polygons == m.polygons);
    }
  }
  REQUIRE(tmp.entries() == 3);  // no temporary files left
}

TEST_CASE("STL round-trips float32 triangles, duplicates corners merged", "[io]") {
  TempDir tmp("stl");
  SurfaceMesh m = awkward_mesh(true);
  // STL stores triangles only and no indices: use a mesh whose vertices are all distinct and
  // appear in index order.
  SurfaceMesh t;
  t.V = m.V.topRows(9);
  t.F.resize(4, 3);
  t.F << 0, 1, 2, 1, 3, 2, 4, 5, 6, 6, 7, 8;
  for (Encoding enc : {Encoding::ascii, Encoding::binary}) {
    write_surface(tmp / "m.stl", t, enc);
    const SurfaceMesh r = read_surface(tmp / "m.stl");
    require_same(t, r);
  }
  // Binary file size is exactly 84 + 50 * triangles.
  REQUIRE(fs::file_size(tmp / "m.stl") == 84u + 50u * 4u);
}

TEST_CASE("OBJ reader: texture/normal indices, negative indices, comments", "[io]") {
  TempDir tmp("obj");
  write_text(tmp / "a.obj",
             "# comment\nv 0 0 0\nv 1 0 0\nvt 0 0\nv 0 1 0 # trailing\nvn 0 0 1\n\n"
             "f 1/1/1 2//1 3/1\nv 0 0 1\nf -1 -3 -2\ng x\ns off\n");
  const SurfaceMesh r = read_surface(tmp / "a.obj");
  REQUIRE(r.V.rows() == 4);
  REQUIRE(r.F.rows() == 2);
  REQUIRE(r.F.row(0) == Eigen::RowVector3i(0, 1, 2));
  REQUIRE(r.F.row(1) == Eigen::RowVector3i(3, 1, 2));
}

TEST_CASE("point lists round-trip with %.17g, comments and blank lines", "[io]") {
  TempDir tmp("points");
  std::mt19937_64 rng(3);
  for (int d : {2, 3}) {
    Eigen::MatrixXd P(17, d);
    for (Eigen::Index i = 0; i < P.size(); ++i) P.data()[i] = awkward(rng);
    write_points(tmp / "p.xyz", P);
    const Eigen::MatrixXd R = read_points(tmp / "p.xyz");
    REQUIRE(R.rows() == P.rows());
    REQUIRE(R.cols() == P.cols());
    REQUIRE((R.array() == P.array()).all());
  }
  write_text(tmp / "c.txt", "# header\n\n1 2 3\n  4,5,6  # comment\n\n");
  const Eigen::MatrixXd R = read_points(tmp / "c.txt");
  REQUIRE(R.rows() == 2);
  REQUIRE(R(1, 2) == 6.0);
}

TEST_CASE("TetGen files round-trip exactly, 3D and 2D", "[io]") {
  TempDir tmp("tetgen");
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  // Two tetrahedra sharing a face, and two triangles, with full-precision coordinates.
  Eigen::MatrixXd U(5, 3);
  U << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  for (Eigen::Index i = 0; i < U.size(); ++i) U.data()[i] += jitter(rng);
  Eigen::MatrixXi T(2, 4);
  T << 0, 1, 2, 3, 1, 2, 3, 4;
  Eigen::MatrixXi B(2, 3);
  B << 0, 1, 2, 1, 3, 4;
  write_tetgen(tmp / "c", U, T, B);
  for (const char* name : {"c", "c.node", "c.ele"}) {
    const ControlMesh m = read_tetgen(tmp / name);
    REQUIRE(m.dim() == 3);
    REQUIRE((m.U.array() == U.array()).all());
    REQUIRE(m.T == T);
  }
  REQUIRE(slurp(tmp / "c.face") == "2 0\n0 0 1 2\n1 1 3 4\n");  // written, never read
  REQUIRE((read_node(tmp / "c.node").array() == U.array()).all());
  REQUIRE(read_control_mesh(tmp / "c.ele").T == T);

  Eigen::MatrixXd U2(4, 2);
  U2 << 0, 0, 1, 0, 1, 1, 0, 1;
  for (Eigen::Index i = 0; i < U2.size(); ++i) U2.data()[i] += jitter(rng);
  Eigen::MatrixXi T2(2, 3);
  T2 << 0, 1, 2, 0, 2, 3;
  write_tetgen(tmp / "s.node", U2, T2);
  const ControlMesh m2 = read_tetgen(tmp / "s");
  REQUIRE(m2.dim() == 2);
  REQUIRE((m2.U.array() == U2.array()).all());
  REQUIRE(m2.T == T2);
}

TEST_CASE("TetGen reader: 1-based numbering, attributes, markers, comments", "[io]") {
  TempDir tmp("tetgen1");
  write_text(tmp / "a.node",
             "# points\n5 3 2 1\n1 0 0 0 7 8 1\n2 1 0 0 7 8 1\n3 0 1 0 7 8 0\n"
             "4 0 0 1 7 8 0 # c\n5 1 1 1 7 8 1\n");
  write_text(tmp / "a.ele", "2 4 1\n1 1 2 3 4 9\n2 2 3 4 5 9\n");
  write_text(tmp / "a.face", "1 1\n1 1 2 3 -1\n");
  const ControlMesh m = read_tetgen(tmp / "a.face");  // the base name, from any companion
  REQUIRE(m.U.rows() == 5);
  REQUIRE(m.U(4, 2) == 1.0);
  REQUIRE(m.T.row(0) == Eigen::RowVector4i(0, 1, 2, 3));
  REQUIRE(m.T.row(1) == Eigen::RowVector4i(1, 2, 3, 4));
}

TEST_CASE("Gmsh 2.2 and 4.1: tetrahedra kept, other types skipped, every node kept in file order", "[io]") {
  TempDir tmp("gmsh");
  // Node tags 10..50 in an odd order; node 99 used only by a point element (dropped).
  write_text(tmp / "a.msh",
             "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"vol\"\n"
             "$EndPhysicalNames\n$Nodes\n6\n30 0 1 0\n10 0 0 0\n20 1 0 0\n40 0 0 1\n"
             "50 1 1 1\n99 5 5 5\n$EndNodes\n$Elements\n5\n1 15 2 0 1 99\n2 2 2 0 1 10 20 30\n"
             "3 4 2 1 1 10 20 30 40\n4 4 2 1 1 20 30 40 50\n5 1 2 0 1 10 20\n$EndElements\n");
  write_text(tmp / "b.msh",
             "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n"
             "$EndEntities\n$Nodes\n2 6 10 99\n0 1 0 1\n99\n5 5 5\n3 1 0 5\n30\n10\n20\n40\n50\n"
             "0 1 0\n0 0 0\n1 0 0\n0 0 1\n1 1 1\n$EndNodes\n$Elements\n2 3 1 3\n"
             "2 1 2 1\n1 10 20 30\n3 1 4 2\n2 10 20 30 40\n3 20 30 40 50\n$EndElements\n");
  for (const char* name : {"a.msh", "b.msh"}) {
    INFO(name);
    const ControlMesh m = read_control_mesh(tmp / name);
    REQUIRE(m.dim() == 3);
    REQUIRE(m.U.rows() == 6);  // node 99 (a point element only) kept, as TetGen's .node would
    REQUIRE(m.T.rows() == 2);
    // Nodes in file order: a.msh 30, 10, 20, 40, 50, 99; b.msh 99, 30, 10, 20, 40, 50.
    const int o = std::string(name) == "b.msh" ? 1 : 0;
    REQUIRE(m.U.row(o) == Eigen::RowVector3d(0, 1, 0));
    REQUIRE(m.T.row(0) == Eigen::RowVector4i(1 + o, 2 + o, o, 3 + o));
    REQUIRE(m.T.row(1) == Eigen::RowVector4i(2 + o, o, 3 + o, 4 + o));
  }
  // 2D: triangles only, z = 0 dropped.
  write_text(tmp / "c.msh",
             "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n"
             "4 0 1 0\n$EndNodes\n$Elements\n3\n1 2 0 1 2 3\n2 2 0 1 3 4\n3 1 0 1 2\n$EndElements\n");
  const ControlMesh c = read_gmsh(tmp / "c.msh");
  REQUIRE(c.dim() == 2);
  REQUIRE(c.T.rows() == 2);
  REQUIRE(c.T.row(1) == Eigen::RowVector3i(0, 2, 3));
}

TEST_CASE("VTK output: counts, cell types and exact coordinates", "[io]") {
  TempDir tmp("vtk");
  Eigen::MatrixXd U(4, 3);
  U << 0.1, 0.2, 0.3, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Eigen::MatrixXi T(1, 4);
  T << 0, 1, 2, 3;
  Eigen::MatrixXd D = Eigen::MatrixXd::Constant(4, 3, 0.5);
  write_vtk(tmp / "a.vtk", U, T, D);
  const std::string s = slurp(tmp / "a.vtk");
  REQUIRE(s.rfind("# vtk DataFile Version 3.0\n", 0) == 0);
  REQUIRE(s.find("DATASET UNSTRUCTURED_GRID") != std::string::npos);
  REQUIRE(s.find("POINTS 4 double\n0.10000000000000001 0.20000000000000001 0.29999999999999999\n") !=
          std::string::npos);
  REQUIRE(s.find("CELLS 1 5\n4 0 1 2 3\n") != std::string::npos);
  REQUIRE(s.find("CELL_TYPES 1\n10\n") != std::string::npos);
  REQUIRE(s.find("POINT_DATA 4\nVECTORS displacement double\n") != std::string::npos);
  Eigen::MatrixXd U2(3, 2);
  U2 << 0, 0, 1, 0, 0, 1;
  Eigen::MatrixXi T2(1, 3);
  T2 << 0, 1, 2;
  write_vtk(tmp / "b.vtk", U2, T2);
  REQUIRE(slurp(tmp / "b.vtk").find("CELL_TYPES 1\n5\n") != std::string::npos);
}

TEST_CASE("PC2: header layout, appended frames, atomic finish", "[io]") {
  TempDir tmp("pc2");
  std::mt19937_64 rng(5);
  std::vector<Eigen::MatrixXd> frames;
  {
    Pc2Writer w(tmp / "a.pc2", 6, 2.0f, 0.5f);
    for (int s = 0; s < 3; ++s) {
      Eigen::MatrixXd P(6, 3);
      for (Eigen::Index i = 0; i < P.size(); ++i) P.data()[i] = awkward(rng) * 1e-20;
      frames.push_back(P);
      w.append(P);
      REQUIRE_FALSE(fs::exists(tmp / "a.pc2"));  // not visible before finish()
    }
    REQUIRE_THROWS_AS(w.append(Eigen::MatrixXd::Zero(5, 3)), mbi::io::Error);
    w.finish();
  }
  REQUIRE(fs::file_size(tmp / "a.pc2") == 32u + 3u * 6u * 12u);
  const std::string raw = slurp(tmp / "a.pc2");
  REQUIRE(std::memcmp(raw.data(), "POINTCACHE2\0", 12) == 0);
  std::int32_t header[5];
  std::memcpy(header, raw.data() + 12, 20);
  REQUIRE(header[0] == 1);
  REQUIRE(header[1] == 6);
  REQUIRE(header[4] == 3);
  const PointCache pc = read_pc2(tmp / "a.pc2");
  REQUIRE(pc.start_frame == 2.0f);
  REQUIRE(pc.sample_rate == 0.5f);
  REQUIRE(pc.frames.size() == 3);
  for (int s = 0; s < 3; ++s)
    for (Eigen::Index i = 0; i < 18; ++i)
      REQUIRE(pc.frames[static_cast<std::size_t>(s)].data()[i] ==
              static_cast<double>(static_cast<float>(frames[static_cast<std::size_t>(s)].data()[i])));
  // Abandoned writer: no target, no temporary file.
  {
    Pc2Writer w(tmp / "b.pc2", 2);
    w.append(Eigen::MatrixXd::Ones(2, 3));
  }
  REQUIRE_FALSE(fs::exists(tmp / "b.pc2"));
  REQUIRE(tmp.entries() == 1);
  Pc2Writer w(tmp / "c.pc2", 1);
  Eigen::MatrixXd bad(1, 3);
  bad << 0, std::nan(""), 0;
  REQUIRE_THROWS_AS(w.append(bad), mbi::io::Error);
}

TEST_CASE("frame sequences: names and contents", "[io]") {
  TempDir tmp("frames");
  REQUIRE(frame_path(tmp / "bunny", 7, ".obj") == tmp / "bunny_0007.obj");
  REQUIRE(frame_path("x", 12345, ".ply", 3) == fs::path("x_12345.ply"));
  REQUIRE_THROWS_AS(frame_path("x", -1, ".obj"), mbi::io::Error);
  const SurfaceMesh m = awkward_mesh(false);
  const Eigen::MatrixXd V2 = 2.0 * m.V;
  for (const char* ext : {".obj", ".ply"}) {
    const fs::path p = write_frame(tmp / "f", 3, ext, m, V2, Encoding::binary);
    const SurfaceMesh r = read_surface(p);
    REQUIRE((r.V.array() == V2.array()).all());
    REQUIRE(r.polygons == m.polygons);
  }
  REQUIRE_THROWS_AS(write_frame(tmp / "f", 4, ".obj", m, V2.topRows(3)), mbi::io::Error);
}

TEST_CASE("writers reject bad data and leave the target untouched", "[io]") {
  TempDir tmp("atomic");
  SurfaceMesh m = awkward_mesh(false);
  write_surface(tmp / "m.obj", m);
  const std::string before = slurp(tmp / "m.obj");
  m.V(3, 1) = std::numeric_limits<double>::quiet_NaN();
  require_io_error([&] { write_surface(tmp / "m.obj", m); }, tmp / "m.obj", 0, "vertex 3");
  m = awkward_mesh(false);
  m.polygons[1][2] = 99;
  require_io_error([&] { write_surface(tmp / "m.obj", m); }, tmp / "m.obj", 0, "face 1");
  REQUIRE(slurp(tmp / "m.obj") == before);
  REQUIRE(tmp.entries() == 1);
  require_io_error([&] { write_points(tmp / "nope" / "p.txt", Eigen::MatrixXd::Ones(2, 2)); },
                   tmp / "nope" / "p.txt", 0, "folder");
  Eigen::MatrixXi T(1, 4);
  T << 0, 1, 2, 7;
  require_io_error([&] { write_tetgen(tmp / "c", Eigen::MatrixXd::Ones(4, 3), T); },
                   tmp / "c.ele", 0, "element 0");
  REQUIRE_FALSE(fs::exists(tmp / "c.node"));
}

TEST_CASE("malformed text files: mbi::io::Error naming file, line and field", "[io][robustness]") {
  TempDir tmp("bad");
  struct Case {
    const char* name;
    std::string text;
    int line;
    const char* what;
  };
  const std::vector<Case> cases = {
      {"a.obj", "v 1 2\n", 1, "vertex 0"},
      {"b.obj", "v 0 0 0\nv 1 nan 0\n", 2, "non-finite"},
      {"c.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n", 5, "face 0"},
      {"d.obj", "v 0 0 0\nf 1 1\n", 2, "fewer than 3"},
      {"e.obj", "v 0 0 1e999\n", 1, "out of range"},
      {"f.obj", "v 0 0 0\nf 0 1 1\n", 2, "index 0"},
      {"g.obj", "v 0 0 0\nf 1 x 1\n", 2, "not an integer"},
      {"a.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n", 2, "only 2 data lines"},
      {"b.off", "OFF\n2000000000 1 0\n0 0 0\n", 2, "2000000000 vertices"},
      {"c.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", 6, "face 0 index"},
      {"d.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", 4, "vertex 1"},
      {"e.off", "OFX\n3 1 0\n", 1, "OFF"},
      {"f.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", 6, "vertex count"},
      {"a.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
       "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
       "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
       13, "index"},
      {"b.ply",
       "ply\nformat ascii 1.0\nelement vertex 1500000000\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n0 0 0\n",
       0, "1500000000 elements"},
      {"c.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n0 nan 0\n",
       8, "vertex 0 y"},
      {"d.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", 0, "end_header"},
      {"e.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "end_header\n0 0\n",
       3, "x, y, z"},
      {"a.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n"
                "endfacet\nendsolid\n", 7, "expected 3 vertices"},
      {"b.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", 2, "not closed"},
      {"c.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 nan 0\n", 4, "non-finite"},
      {"a.xyz", "1 2 3\n4 5\n", 2, "point 1"},
      {"b.xyz", "1 2 3\n4 5 nan\n", 2, "non-finite"},
      {"a.node", "2000000000 3 0 0\n0 0 0 0\n", 1, "2000000000 points"},
      {"b.node", "2 3 0 0\n0 0 0 0\n2 1 0 0\n", 3, "consecutive"},
      {"c.node", "2 3 0 0\n0 0 0 0\n1 1 nan 0\n", 3, "point 1 coordinate 1"},
      {"d.node", "2 4 0 0\n0 0 0 0 0\n1 1 0 0 0\n", 1, "dimension"},
      {"e.node", "2 3 0 0\n5 0 0 0\n6 1 0 0\n", 2, "0 or 1"},
      {"f.node", "2 3 1 1\n0 0 0 0\n1 1 0 0\n", 2, "expected 6 values"},
      {"a.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1999999999\n1 0 0 0\n$EndNodes\n",
       5, "1999999999 nodes"},
      {"b.msh", "$MeshFormat\n2.2 1 8\n$EndMeshFormat\n", 0, "binary: expected the int 1"},
      {"c.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n"
                "$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n", 10, "unknown node tag 2"},
      {"d.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n2 0 0 0\n3 0 0 0\n"
                "$EndNodes\n", 8, "$EndNodes"},
      {"e.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1000000000 1 1\n0 1 0 1\n",
       5, "1000000000 nodes"},
      {"f.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 nan\n$EndNodes\n", 6,
       "node 1 coordinate 2"},
      {"g.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n", 0,
       "no tetrahedra"},
  };
  for (const auto& c : cases) {
    INFO(c.name << ": " << c.what);
    write_text(tmp / c.name, c.text);
    const std::string ext = fs::path(c.name).extension().string();
    require_io_error(
        [&] {
          if (ext == ".xyz") read_points(tmp / c.name);
          else if (ext == ".node") read_node(tmp / c.name);
          else if (ext == ".msh") read_control_mesh(tmp / c.name);
          else read_surface(tmp / c.name);
        },
        tmp / c.name, c.line, c.what);
  }
  require_io_error([&] { read_surface(tmp / "missing.obj"); }, tmp / "missing.obj", 0, "open");
  require_io_error([&] { read_surface(tmp / "x.abc"); }, tmp / "x.abc", 0, "unknown surface");
}

TEST_CASE("malformed TetGen element files, .face files are not read", "[io][robustness]") {
  TempDir tmp("badele");
  write_text(tmp / "m.node", "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 0\n");
  struct Case {
    std::string ele;
    int line;
    const char* what;
  };
  const std::vector<Case> cases = {
      {"1 4 0\n0 0 1 2 7\n", 2, "element 0 node"},
      {"3 4 0\n0 0 1 2 3\n", 1, "3 elements"},
      {"1 4 0\n0 0 1 2 2\n", 2, "repeated"},
      {"1 4 0\n0 0 1 2 4\n", 2, "degenerate"},  // four points in the plane z = 0
      {"1 5 0\n0 0 1 2 3 4\n", 1, "nodes per element"},
      {"1 4 0\n0 0 1 2\n", 2, "expected 4 node numbers"},
      {"1 4 0\n0 0 1 -2 3\n", 2, "out of range"},
  };
  for (const auto& c : cases) {
    INFO(c.ele);
    write_text(tmp / "m.ele", c.ele);
    require_io_error([&] { read_tetgen(tmp / "m"); }, tmp / "m.ele", c.line, c.what);
  }
  // a stale or broken .face beside them is not read (nothing uses it)
  write_text(tmp / "m.ele", "1 4 0\n0 0 1 2 3\n");
  for (const char* face : {"1 0\n0 0 1 9\n", "1000000000 0\n0 0 1 2\n", "garbage\n"}) {
    write_text(tmp / "m.face", face);
    REQUIRE(read_tetgen(tmp / "m").T.rows() == 1);
  }
}

TEST_CASE("malformed binary files: absurd counts and truncation", "[io][robustness]") {
  TempDir tmp("badbin");
  const std::string head =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\n"
      "property double y\nproperty double z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n";
  auto vertices = [](double nan_at) {
    std::string s;
    for (int i = 0; i < 9; ++i) {
      const double x = i == 4 ? nan_at : static_cast<double>(i % 3 == 0);
      s.append(reinterpret_cast<const char*>(&x), 8);
    }
    return s;
  };
  auto face = [](std::uint8_t k, std::int32_t a, std::int32_t b, std::int32_t c) {
    std::string s(1, static_cast<char>(k));
    for (std::int32_t x : {a, b, c}) s.append(reinterpret_cast<const char*>(&x), 4);
    return s;
  };
  // Valid file first, to make sure the failures below are about what they change.
  write_text(tmp / "ok.ply", head + vertices(0.0) + face(3, 0, 1, 2));
  REQUIRE(read_surface(tmp / "ok.ply").F.rows() == 1);
  write_text(tmp / "a.ply", head + vertices(0.0) + face(3, 0, 1, 3));
  require_io_error([&] { read_surface(tmp / "a.ply"); }, tmp / "a.ply", 0, "face 0: index 3");
  write_text(tmp / "b.ply", head + vertices(std::nan("")) + face(3, 0, 1, 2));
  require_io_error([&] { read_surface(tmp / "b.ply"); }, tmp / "b.ply", 0, "vertex 1");
  write_text(tmp / "c.ply", head + vertices(0.0) + face(3, 0, 1, 2).substr(0, 7));
  require_io_error([&] { read_surface(tmp / "c.ply"); }, tmp / "c.ply", 0, "face 0");
  std::string absurd = head;
  absurd.replace(absurd.find("vertex 3"), 8, "vertex 2000000000");
  write_text(tmp / "d.ply", absurd + vertices(0.0));
  require_io_error([&] { read_surface(tmp / "d.ply"); }, tmp / "d.ply", 0, "bytes");
  write_text(tmp / "e.ply", head + vertices(0.0) + face(250, 0, 1, 2));
  require_io_error([&] { read_surface(tmp / "e.ply"); }, tmp / "e.ply", 0, "exceeds the file size");

  // Binary STL whose triangle count does not match the file size.
  std::string stl(80, ' ');
  const std::uint32_t n = 4000000000u;
  stl.append(reinterpret_cast<const char*>(&n), 4);
  stl.append(50, '\0');
  write_text(tmp / "a.stl", stl);
  require_io_error([&] { read_surface(tmp / "a.stl"); }, tmp / "a.stl", 0, "4000000000 triangles");

  // PC2: absurd counts, truncated data, wrong magic.
  std::string pc2("POINTCACHE2\0", 12);
  const std::int32_t h[5] = {1, 1000000, 0, 0, 1000000};
  pc2.append(reinterpret_cast<const char*>(h), 20);
  write_text(tmp / "a.pc2", pc2);
  require_io_error([&] { read_pc2(tmp / "a.pc2"); }, tmp / "a.pc2", 0, "1000000 points");
  write_text(tmp / "b.pc2", pc2.substr(0, 20));
  require_io_error([&] { read_pc2(tmp / "b.pc2"); }, tmp / "b.pc2", 0, "too short");
  write_text(tmp / "c.pc2", "POINTCACHE3" + pc2.substr(11));
  require_io_error([&] { read_pc2(tmp / "c.pc2"); }, tmp / "c.pc2", 0, "magic");
}

TEST_CASE("real models: read, write, read again gives the same mesh", "[io][models]") {
  const std::string dir = mbi::test::models_dir_or_skip().string();
  TempDir tmp("models");
  for (const char* name : {"alligator", "fandisk", "spot", "stanford-bunny", "woody"}) {
    INFO(name);
    const fs::path p = fs::path(dir) / (std::string(name) + ".obj");
    if (!fs::exists(p)) {
      WARN(p << " missing: skipped");
      continue;
    }
    const SurfaceMesh m = read_surface(p);
    REQUIRE(m.V.rows() > 0);
    REQUIRE(m.F.rows() > 0);
    if (std::string(name) == "stanford-bunny") REQUIRE(m.V.rows() == 35947);
    REQUIRE(m.F.minCoeff() >= 0);
    REQUIRE(m.F.maxCoeff() < m.V.rows());
    write_surface(tmp / "m.ply", m, Encoding::binary);
    require_same(m, read_surface(tmp / "m.ply"));
  }
}

TEST_CASE("truncated and corrupted files of every format: mbi::io::Error or success, nothing else",
          "[io][robustness]") {
  TempDir tmp("fuzz");
  const SurfaceMesh m = awkward_mesh(true);
  SurfaceMesh tri;
  tri.V = m.V;
  tri.F = m.F;
  Eigen::MatrixXd U(5, 3);
  U << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  Eigen::MatrixXi T(2, 4);
  T << 0, 1, 2, 3, 1, 2, 3, 4;
  // Valid originals.
  write_surface(tmp / "s.obj", m);
  write_surface(tmp / "s.off", m);
  write_surface(tmp / "a.ply", m, Encoding::ascii);
  write_surface(tmp / "b.ply", m, Encoding::binary);
  write_surface(tmp / "a.stl", tri, Encoding::ascii);
  write_surface(tmp / "b.stl", tri, Encoding::binary);
  write_points(tmp / "p.xyz", U);
  write_tetgen(tmp / "c", U, T);
  {
    Pc2Writer w(tmp / "c.pc2", 5);
    w.append(U);
    w.append(U);
    w.finish();
  }
  write_text(tmp / "g.msh",
             "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 5 1 5\n3 1 0 5\n1\n2\n3\n4\n5\n"
             "0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n$EndNodes\n$Elements\n1 2 1 2\n3 1 4 2\n"
             "1 1 2 3 4\n2 2 3 4 5\n$EndElements\n");
  struct Reader {
    const char* file;
    std::function<void(const fs::path&)> read;
  };
  const std::vector<Reader> readers = {
      {"s.obj", [](const fs::path& p) { read_surface(p); }},
      {"s.off", [](const fs::path& p) { read_surface(p); }},
      {"a.ply", [](const fs::path& p) { read_surface(p); }},
      {"b.ply", [](const fs::path& p) { read_surface(p); }},
      {"a.stl", [](const fs::path& p) { read_surface(p); }},
      {"b.stl", [](const fs::path& p) { read_surface(p); }},
      {"p.xyz", [](const fs::path& p) { read_points(p); }},
      {"c.node", [](const fs::path& p) { read_node(p); }},
      {"c.ele", [](const fs::path& p) { read_tetgen(p); }},
      {"c.pc2", [](const fs::path& p) { read_pc2(p); }},
      {"g.msh", [](const fs::path& p) { read_gmsh(p); }},
  };
  std::mt19937 rng(2024);
  const std::string junk[] = {"-1", "nan", "99999999999", "x", "\n", " ", "0", "1e308", "\xff"};
  int errors = 0, successes = 0;
  for (const auto& r : readers) {
    const fs::path orig = tmp / r.file;
    const std::string good = slurp(orig);
    REQUIRE_NOTHROW(r.read(orig));
    auto attempt = [&](const std::string& bytes) {
      write_text(orig, bytes);
      try {
        r.read(orig);
        ++successes;
      } catch (const mbi::io::Error& e) {
        ++errors;
        REQUIRE(std::string(e.what()).find(orig.string()) != std::string::npos);
      }
    };
    const std::size_t stride = std::max<std::size_t>(1, good.size() / 400);
    for (std::size_t len = 0; len < good.size(); len += stride) attempt(good.substr(0, len));
    for (int k = 0; k < 300; ++k) {
      std::string bad = good;
      const std::size_t at = rng() % bad.size();
      switch (k % 3) {
        case 0: bad[at] = static_cast<char>(rng() & 0xff); break;
        case 1: bad.erase(at, 1 + rng() % 8); break;
        default: bad.insert(at, junk[rng() % std::size(junk)]); break;
      }
      attempt(bad);
    }
    write_text(orig, good);
  }
  INFO(errors << " errors, " << successes << " successes");
  REQUIRE(errors > 1000);  // the corruptions were mostly detected, not silently accepted
}
