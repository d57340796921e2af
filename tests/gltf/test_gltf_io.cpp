// glTF 2.0 in and out (mbi::io): the three.js-written fixture read as placed parts with their
// materials and UVs; a static and an animated file read back; skins, morph targets and broken
// accessors refused with a message naming the node and accessor.
#include <mbi/io/io.hpp>

#include "common/files.hpp"
#include "common/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <sys/stat.h>

#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using mbi::test::TempDir;
using nlohmann::json;

namespace {

fs::path fixture() { return mbi::test::source_dir() / "tests" / "gltf" / "data" / "parts.glb"; }

std::string base64(const std::string& b) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string s;
  for (std::size_t i = 0; i < b.size(); i += 3) {
    unsigned v = static_cast<unsigned char>(b[i]) << 16;
    if (i + 1 < b.size()) v |= static_cast<unsigned char>(b[i + 1]) << 8;
    if (i + 2 < b.size()) v |= static_cast<unsigned char>(b[i + 2]);
    s += k[(v >> 18) & 63];
    s += k[(v >> 12) & 63];
    s += i + 1 < b.size() ? k[(v >> 6) & 63] : '=';
    s += i + 2 < b.size() ? k[v & 63] : '=';
  }
  return s;
}

// A glTF of one triangle (positions, uint16 indices) under one node, as JSON to edit.
json one_triangle() {
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::uint16_t idx[4] = {0, 1, 2, 0};
  std::string bytes(44, '\0');
  std::memcpy(bytes.data(), p, 36);
  std::memcpy(bytes.data() + 36, idx, 8);
  json j = json::parse(R"({
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"name": "tri", "mesh": 0, "translation": [1, 2, 3]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}]})");
  j["buffers"] = json::array({{{"byteLength", 44}, {"uri", "data:application/octet-stream;base64," + base64(bytes)}}});
  return j;
}

fs::path write_json(const TempDir& dir, const json& j, const std::string& name = "t.gltf") {
  const fs::path p = dir / name;
  std::ofstream(p) << j.dump();
  return p;
}

std::string error_of(const fs::path& p) {
  try {
    mbi::io::read_surface(p);
  } catch (const mbi::io::Error& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("glTF in: the three.js fixture's parts, placed by their nodes", "[io][gltf]") {
  const mbi::io::SurfaceMesh m = mbi::io::read_surface(fixture());
  // body, head (child of body), two wheels sharing one mesh: four parts
  REQUIRE(m.V.rows() > 100);
  REQUIRE(m.N.rows() == m.V.rows());
  CHECK((m.N.rowwise().norm().array() - 1).abs().maxCoeff() < 1e-6);
  CHECK(m.F.maxCoeff() < m.V.rows());
  // the box (2 x 0.8 x 1, centred on its node) sits at the root's translation (0.5, 0.2, -0.3)
  // turned by 30 degrees about y: its centre is the root's origin
  const Eigen::RowVector3d lo = m.V.colwise().minCoeff(), hi = m.V.colwise().maxCoeff();
  CHECK(lo.y() == Approx(-0.75 + 0.2).margin(1e-6));  // the wheels' bottom: -0.45 - 0.3
  CHECK(hi.y() > 0.2 + 0.7);                          // the head is above the body
  // written back: the same parts, positions to float32, the same faces
  TempDir dir("gltf_io");
  for (const char* name : {"back.glb", "back.gltf"}) {
    mbi::io::write_surface(dir / name, m);
    const mbi::io::SurfaceMesh b = mbi::io::read_surface(dir / name);
    REQUIRE(b.V.rows() == m.V.rows());
    CHECK((b.V - m.V).cwiseAbs().maxCoeff() < 1e-6);
    CHECK(b.F == m.F);
    CHECK((b.N - m.N).cwiseAbs().maxCoeff() < 1e-6);
  }
  // a surface of another format becomes one part
  mbi::io::write_surface(dir / "m.obj", m);
  const mbi::io::SurfaceMesh obj = mbi::io::read_surface(dir / "m.obj");
  mbi::io::write_surface(dir / "from_obj.glb", obj);
  CHECK(mbi::io::read_surface(dir / "from_obj.glb").F == m.F);
}

TEST_CASE("glTF out: an animation reads back as its first frame and its times must increase", "[io][gltf]") {
  const mbi::io::SurfaceMesh m = mbi::io::read_surface(fixture());
  TempDir dir("gltf_anim");
  mbi::io::GltfWriter w(dir / "anim.glb", m);
  for (int k = 0; k < 3; ++k) {
    Eigen::MatrixXd V = m.V;
    V.col(0).array() += 0.5 * k;
    w.append(k / 24.0, V, m.N);
  }
  CHECK_THROWS_WITH(w.append(0.0, m.V, m.N), Catch::Contains("anim.glb: frame 3: time"));
  CHECK(w.samples() == 3);
  CHECK_FALSE(fs::exists(dir / "anim.glb"));  // written by finish() only
  w.finish();
  const mbi::io::SurfaceMesh b = mbi::io::read_surface(dir / "anim.glb");
  REQUIRE(b.V.rows() == m.V.rows());
  CHECK((b.V - m.V).cwiseAbs().maxCoeff() < 1e-6);
}

TEST_CASE("glTF in: node transforms, and skins, morph targets and bad accessors refused by name", "[io][gltf]") {
  TempDir dir("gltf_bad");
  const mbi::io::SurfaceMesh t = mbi::io::read_surface(write_json(dir, one_triangle()));
  REQUIRE(t.V.rows() == 3);
  CHECK(t.V.row(1) == Eigen::RowVector3d(2, 2, 3));  // translated by the node

  json skinned = one_triangle();
  skinned["nodes"][0]["skin"] = 0;
  skinned["skins"] = json::array({{{"joints", {0}}}});
  CHECK_THAT(error_of(write_json(dir, skinned)), Catch::Contains("t.gltf: node 0 'tri': a skinned mesh (skin 0) is not read"));

  json morph = one_triangle();
  morph["meshes"][0]["primitives"][0]["targets"] = json::array({{{"POSITION", 0}}});
  CHECK_THAT(error_of(write_json(dir, morph)), Catch::Contains("mesh 0 primitive 0: morph targets are not read"));

  json lines = one_triangle();
  lines["meshes"][0]["primitives"][0]["mode"] = 1;
  CHECK_THAT(error_of(write_json(dir, lines)), Catch::Contains("mode 1 is not read"));

  json past = one_triangle();
  past["accessors"][0]["count"] = 4;  // 48 bytes in a view of 36
  const std::string e = error_of(write_json(dir, past));
  CHECK_THAT(e, Catch::Contains("t.gltf") && (Catch::Contains("accessor") || Catch::Contains("not a readable glTF")));

  json index = one_triangle();
  index["accessors"][1]["count"] = 2;
  CHECK_THAT(error_of(write_json(dir, index)), Catch::Contains("indices: 2 indices is not a whole number of triangles"));

  CHECK_THAT(error_of(write_json(dir, json::parse(R"({"asset": {"version": "2.0"}})"))), Catch::Contains("no scene"));
  json cycle = one_triangle();  // nodes form trees
  cycle["nodes"][0]["children"] = {0};
  CHECK_THAT(error_of(write_json(dir, cycle)), Catch::Contains("node 0 'tri': reached twice"));
  json float_index = one_triangle();
  float_index["accessors"][1] = {{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "SCALAR"}};
  CHECK_THAT(error_of(write_json(dir, float_index)), Catch::Contains("indices") && Catch::Contains("is not"));
  json device = one_triangle();  // a buffer is read only from a regular file in the asset's folder
  device["buffers"][0]["uri"] = "/dev/zero";
  CHECK_THAT(error_of(write_json(dir, device)), Catch::Contains("t.gltf: buffer 0: uri '/dev/zero' is not read"));
  REQUIRE(mkfifo((dir / "fifo.bin").c_str(), 0600) == 0);
  device["buffers"][0]["uri"] = "fifo.bin";
  CHECK_THAT(error_of(write_json(dir, device)), Catch::Contains("t.gltf: not a readable glTF 2.0 file"));
  std::ofstream(dir / "junk.glb") << "glTF but not really";
  CHECK_THAT(error_of(dir / "junk.glb"), Catch::Contains("junk.glb: not a readable glTF 2.0 file"));
}
