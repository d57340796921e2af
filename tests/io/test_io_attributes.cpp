// Attribute pass-through of the surface formats: whatever a file holds besides
// positions is written back unchanged, normals are replaced by the ones given, binary stays
// binary with its endianness, and a mesh without faces writes a vertices-only file.
#include <mbi/io/io.hpp>

#include "common/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <common/files.hpp>

#include <algorithm>
#include <bit>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace mbi::io;
using mbi::test::TempDir;

namespace {

void write_bytes(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary);
  out << s;
}

std::vector<std::string> lines_of(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

/// Lines of `text` whose first word is one of `keys`, in order.
std::vector<std::string> records(const std::string& text, std::initializer_list<const char*> keys) {
  std::vector<std::string> out;
  for (const auto& l : lines_of(text)) {
    const std::string w = l.substr(0, l.find(' '));
    if (std::find(keys.begin(), keys.end(), w) != keys.end()) out.push_back(l);
  }
  return out;
}

// A moved copy of the positions (as a deformation would give).
Eigen::MatrixXd moved(const Eigen::MatrixXd& V) {
  Eigen::MatrixXd W = V;
  W.col(0).array() += 0.125;
  W.col(2) *= 2.0;
  return W;
}

template <typename T>
void put(std::string& s, T x, bool big) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &x, sizeof(T));
  if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
  s.append(reinterpret_cast<const char*>(b), sizeof(T));
}

// A textured quad-and-triangle OBJ as a modelling tool writes it.
const char* kObj =
    "# exported by a tool\n"
    "mtllib quad.mtl\n"
    "o Quad\n"
    "v 0 0 0 1 0 0\n"
    "v 1 0 0 0 1 0\n"
    "v 1 1 0 0 0 1\n"
    "v 0 1 0 1 1 1\n"
    "v 0.5 1.5 0 0.5 0.5 0.5\n"
    "vt 0 0\n"
    "vt 1 0\n"
    "vt 1 1\n"
    "vt 0 1\n"
    "vt 0.5 1\n"
    "vn 0 0 1\n"
    "g body\n"
    "usemtl paint\n"
    "s 1\n"
    "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
    "g roof\n"
    "usemtl tiles\n"
    "s off\n"
    "f -2/-2/-1 -3/-3/-1 -1/-1/-1\n"
    "l 1 2\n";

}  // namespace

TEST_CASE("OBJ keeps vt, groups, objects, materials, smoothing, vertex colours, normals replaced",
          "[io][attributes]") {
  TempDir tmp("obj-attr");
  write_bytes(tmp / "in.obj", kObj);
  SurfaceMesh m = read_surface(tmp / "in.obj");
  REQUIRE(m.V.rows() == 5);
  REQUIRE(m.polygons.size() == 2);
  REQUIRE(m.polygons[1] == std::vector<int>{3, 2, 4});
  REQUIRE(m.N.rows() == 5);
  CHECK(m.N.row(0) == Eigen::RowVector3d(0, 0, 1));
  REQUIRE(m.attributes);

  SECTION("unchanged mesh: every record but the comment comes back, in order") {
    write_surface(tmp / "out.obj", m);
    const std::string out = mbi::test::slurp(tmp / "out.obj");
    const auto keys = {"mtllib", "o", "vt", "g", "usemtl", "s", "l"};
    CHECK(records(out, keys) == records(kObj, keys));
    // vertex colours kept after the positions; one vn per vertex
    CHECK(records(out, {"v"}) == records(kObj, {"v"}));
    CHECK(records(out, {"vn"}).size() == 5);
    // corners keep their texture index, normals index their vertex (absolute indices)
    CHECK(records(out, {"f"}) ==
          std::vector<std::string>{"f 1/1/1 2/2/2 3/3/3 4/4/4", "f 4/4/4 3/3/3 5/5/5"});
    CHECK(out.find("# exported") == std::string::npos);  // comments may go
  }
  SECTION("deformed positions and normals replace the file's; the rest is byte-equal") {
    SurfaceMesh d = m;
    d.V = moved(m.V);
    d.N = Eigen::MatrixXd::Zero(5, 3);
    d.N.col(1).setOnes();
    write_surface(tmp / "out.obj", d);
    const std::string out = mbi::test::slurp(tmp / "out.obj");
    const auto keys = {"mtllib", "o", "vt", "g", "usemtl", "s", "l"};
    CHECK(records(out, keys) == records(kObj, keys));
    const SurfaceMesh r = read_surface(tmp / "out.obj");
    CHECK(r.V == d.V);
    CHECK(r.N == d.N);
    CHECK(r.polygons == m.polygons);
    CHECK(records(out, {"v"})[1] == "v 1.125 0 0 0 1 0");
  }
  SECTION("without normals: no vn and corners v/vt") {
    SurfaceMesh d = m;
    d.N.resize(0, 0);
    write_surface(tmp / "out.obj", d);
    const std::string out = mbi::test::slurp(tmp / "out.obj");
    CHECK(records(out, {"vn"}).empty());
    CHECK(records(out, {"f"})[1] == "f 4/4 3/3 5/5");
    CHECK(read_surface(tmp / "out.obj").N.size() == 0);
  }
  SECTION("another format gets positions, faces and normals") {
    write_surface(tmp / "out.ply", m);
    const SurfaceMesh r = read_surface(tmp / "out.ply");
    CHECK(r.V == m.V);
    CHECK(r.N == m.N);
    CHECK(r.polygons == m.polygons);
  }
  SECTION("a changed vertex count drops the attributes, not the mesh") {
    SurfaceMesh d = m;
    d.V = m.V.topRows(4);
    d.N.resize(0, 0);
    d.polygons = {{0, 1, 2, 3}};
    write_surface(tmp / "out.obj", d);
    CHECK(records(mbi::test::slurp(tmp / "out.obj"), {"vt", "g"}).empty());
    CHECK(read_surface(tmp / "out.obj").V == d.V);
  }
}

TEST_CASE("OBJ: normals of corners mapped through their vertex, bad vt/vn indices named",
          "[io][attributes]") {
  TempDir tmp("obj-n");
  // vertex 4 has no normal of its own: it gets its faces' (area-weighted) normal
  write_bytes(tmp / "a.obj",
              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 -2\n"
              "f 1//1 3//1 2//1\nf 1 2 4\n");
  const SurfaceMesh m = read_surface(tmp / "a.obj");
  REQUIRE(m.N.rows() == 4);
  CHECK(m.N.row(0) == Eigen::RowVector3d(0, 0, -1));  // normalised
  CHECK(m.N.row(3).isApprox(Eigen::RowVector3d(0, -1, 0)));
  write_bytes(tmp / "b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/2 2/1 3/1\n");
  REQUIRE_THROWS_WITH(read_surface(tmp / "b.obj"),
                      Catch::Contains("b.obj:5: face 0: texture index 2 > number of texture coordinates 1"));
  write_bytes(tmp / "c.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n");
  REQUIRE_THROWS_WITH(read_surface(tmp / "c.obj"),
                      Catch::Contains("c.obj:4: face 0: normal index 1 > number of normals 0"));
}

TEST_CASE("a mesh without faces writes a vertices-only OBJ", "[io][attributes]") {
  TempDir tmp("obj-points");
  SurfaceMesh m;
  m.V = Eigen::MatrixXd::Random(7, 3);
  write_surface(tmp / "p.obj", m);
  const std::string out = mbi::test::slurp(tmp / "p.obj");
  CHECK(records(out, {"v"}).size() == 7);
  CHECK(lines_of(out).size() == 7);
  const SurfaceMesh r = read_surface(tmp / "p.obj");
  CHECK(r.V == m.V);
  CHECK(r.F.rows() == 0);
}

TEST_CASE("ASCII PLY: extra properties and elements come back byte-equal", "[io][attributes]") {
  TempDir tmp("ply-ascii");
  const std::string ply =
      "ply\nformat ascii 1.0\ncomment made by a scanner\nobj_info calibrated\n"
      "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      "property float s\nproperty float t\n"
      "element face 2\nproperty list uchar int vertex_indices\nproperty int flags\n"
      "property list uchar float texcoord\n"
      "element material 1\nproperty float shininess\n"
      "end_header\n"
      "0 0 0 0 0 1 255 0 0 0 0\n"
      "1 0 0 0 0 1 0 255 0 1 0\n"
      "1 1 0 0 0 1 0 0 255 1 1\n"
      "0 1 0 0 0 1 10 20 30 0.1 0.9\n"
      "3 0 1 2 7 6 0 0 1 0 1 1\n"
      "3 0 2 3 -1 6 0 0 1 1 0.1 0.9\n"
      "0.25\n";
  write_bytes(tmp / "in.ply", ply);
  const SurfaceMesh m = read_surface(tmp / "in.ply");
  REQUIRE(m.N.rows() == 4);
  SECTION("unchanged: the whole file") {
    write_surface(tmp / "out.ply", m);
    CHECK(mbi::test::slurp(tmp / "out.ply") == ply);
  }
  SECTION("deformed: positions and normals replaced, every other value as it was") {
    SurfaceMesh d = m;
    d.V = moved(m.V);
    d.N.col(2) *= -1.0;
    write_surface(tmp / "out.ply", d);
    const auto in = lines_of(ply), out = lines_of(mbi::test::slurp(tmp / "out.ply"));
    REQUIRE(in.size() == out.size());
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (i >= 23 && i < 27) {  // vertex lines: colours and texture coordinates kept
        const auto tail = [](const std::string& l) {
          std::size_t p = 0;
          for (int k = 0; k < 6; ++k) p = l.find(' ', p) + 1;
          return l.substr(p);
        };
        CHECK(tail(out[i]) == tail(in[i]));
      } else {
        CHECK(out[i] == in[i]);
      }
    }
    const SurfaceMesh r = read_surface(tmp / "out.ply");
    CHECK(r.V == d.V);  // ASCII positions are written in full whatever the property type
    CHECK(r.N == d.N);
  }
  SECTION("written binary and read back: the same values") {
    write_surface(tmp / "b.ply", m, Encoding::binary);
    CHECK(mbi::test::slurp(tmp / "b.ply").find("format binary_little_endian 1.0") != std::string::npos);
    const SurfaceMesh b = read_surface(tmp / "b.ply");
    write_surface(tmp / "a.ply", b, Encoding::ascii);
    CHECK(mbi::test::slurp(tmp / "a.ply") == ply);
  }
}

TEST_CASE("binary PLY stays binary with the same endianness, every byte of extras kept",
          "[io][attributes]") {
  TempDir tmp("ply-bin");
  for (bool big : {false, true}) {
    INFO((big ? "big" : "little") << " endian");
    std::string ply = std::string("ply\nformat ") +
                      (big ? "binary_big_endian" : "binary_little_endian") +
                      " 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                      "property float z\nproperty ushort quality\nproperty double u\n"
                      "element face 1\nproperty list uchar uint vertex_indices\n"
                      "property uchar part\nend_header\n";
    const float P[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0.5f}};
    for (int i = 0; i < 3; ++i) {
      for (float c : P[i]) put<float>(ply, c, big);
      put<std::uint16_t>(ply, static_cast<std::uint16_t>(1000 + i), big);
      put<double>(ply, 0.1 * i, big);
    }
    put<std::uint8_t>(ply, 3, big);
    for (std::uint32_t i : {0u, 1u, 2u}) put<std::uint32_t>(ply, i, big);
    put<std::uint8_t>(ply, 9, big);
    write_bytes(tmp / "in.ply", ply);
    const SurfaceMesh m = read_surface(tmp / "in.ply");
    write_surface(tmp / "out.ply", m);
    CHECK(mbi::test::slurp(tmp / "out.ply") == ply);  // as read: binary, same endianness, same types
    write_surface(tmp / "bin.ply", m, Encoding::binary);
    CHECK(mbi::test::slurp(tmp / "bin.ply") == ply);
    SurfaceMesh d = m;
    d.V = moved(m.V);
    write_surface(tmp / "d.ply", d);
    const std::string out = mbi::test::slurp(tmp / "d.ply");
    REQUIRE(out.size() == ply.size());
    const std::size_t body = ply.find("end_header\n") + 11;
    for (int i = 0; i < 3; ++i)  // quality and u of each vertex: bytes 12..22 of its record
      CHECK(out.compare(body + 22 * i + 12, 10, ply, body + 22 * i + 12, 10) == 0);
    CHECK(out.compare(body + 66, std::string::npos, ply, body + 66, std::string::npos) == 0);
    CHECK(read_surface(tmp / "d.ply").V == d.V.cast<float>().cast<double>());
  }
}

TEST_CASE("STL: binary stays binary with its header and attribute words, ASCII keeps its name",
          "[io][attributes]") {
  TempDir tmp("stl-attr");
  std::string stl(80, '\0');
  stl.replace(0, 20, "exported by a slicer");
  put<std::uint32_t>(stl, 2, false);
  const float tri[2][3][3] = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{1, 0, 0}, {1, 1, 0}, {0, 1, 0}}};
  for (int t = 0; t < 2; ++t) {
    for (float c : {0.0f, 0.0f, 1.0f}) put<float>(stl, c, false);
    for (const auto& p : tri[t])
      for (float c : p) put<float>(stl, c, false);
    put<std::uint16_t>(stl, static_cast<std::uint16_t>(0x8000 | (31 * (t + 1))), false);  // colour
  }
  write_bytes(tmp / "in.stl", stl);
  const SurfaceMesh m = read_surface(tmp / "in.stl");
  write_surface(tmp / "out.stl", m);
  CHECK(mbi::test::slurp(tmp / "out.stl") == stl);
  SurfaceMesh d = m;
  d.V = moved(m.V);
  write_surface(tmp / "d.stl", d);
  const std::string out = mbi::test::slurp(tmp / "d.stl");
  REQUIRE(out.size() == stl.size());  // binary
  CHECK(out.compare(0, 84, stl, 0, 84) == 0);
  for (int t = 0; t < 2; ++t) CHECK(out.compare(84 + 50 * t + 48, 2, stl, 84 + 50 * t + 48, 2) == 0);
  CHECK(read_surface(tmp / "d.stl").V == d.V);

  write_bytes(tmp / "a.stl",
              "solid my part\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
              "vertex 0 1 0\nendloop\nendfacet\nendsolid my part\n");
  write_surface(tmp / "a2.stl", read_surface(tmp / "a.stl"));
  const std::string a2 = mbi::test::slurp(tmp / "a2.stl");
  CHECK(a2.rfind("solid my part\n", 0) == 0);
  CHECK(a2.find("endsolid my part\n") != std::string::npos);
}
