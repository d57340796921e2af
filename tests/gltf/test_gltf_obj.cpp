// OBJ and PLY into glTF through mbi deform: an OBJ's UVs (its vertices split at UV seams, every
// frame's positions and normals following the split), groups and MTL materials, a PLY's vertex
// colours. The
// Khronos validator, three.js (tests/gltf/node/obj_corners.mjs: every corner's UV and position
// against the OBJ and a point cache of the same run) and, where installed, Blender's importer read
// the files back.
#include <mbi/io/io.hpp>

#include "common/files.hpp"
#include "common/run_mbi.hpp"
#include "common/skip.hpp"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <cstring>
#include <fstream>

namespace fs = std::filesystem;
using mbi::test::q;
using mbi::test::run_mbi;
using mbi::test::TempDir;

namespace {

fs::path source(const std::string& rel) { return mbi::test::source_dir() / rel; }
fs::path vtu(const std::string& name) { return source("tests/data/vtu/" + name); }

// The crate (tests/gltf/data/crate.obj, its MTL and texture) copied into dir/model.
void copy_crate(const TempDir& dir) {
  fs::create_directories(dir / "model" / "textures");
  for (const char* f : {"crate.obj", "crate.mtl", "textures/checker.png"})
    fs::copy_file(source("tests/gltf/data") / f, dir / "model" / f);
}

std::string deform(const std::string& deformed, const std::string& meshes_and_outs) {
  return "deform --control " + q(vtu("box.node")) + " --deformed " + q(vtu(deformed)) + " " + meshes_and_outs;
}

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

// A .glb's JSON and binary chunks.
std::pair<nlohmann::json, std::string> read_glb(const fs::path& file) {
  const std::string b = mbi::test::slurp(file);
  REQUIRE(b.size() > 20);
  std::uint32_t json_bytes = 0, bin_bytes = 0;
  std::memcpy(&json_bytes, b.data() + 12, 4);
  std::memcpy(&bin_bytes, b.data() + 20 + json_bytes, 4);
  return {nlohmann::json::parse(b.substr(20, json_bytes)), b.substr(28 + json_bytes, bin_bytes)};
}

// Accessor `a` of float components, as read from the binary chunk.
std::vector<float> floats(const nlohmann::json& j, const std::string& bin, int a) {
  const auto& acc = j["accessors"][a];
  const auto& view = j["bufferViews"][acc["bufferView"].get<int>()];
  const std::size_t width = acc["type"] == "VEC4" ? 4 : acc["type"] == "VEC3" ? 3 : acc["type"] == "VEC2" ? 2 : 1;
  std::vector<float> v(acc["count"].get<std::size_t>() * width);
  std::memcpy(v.data(), bin.data() + view["byteOffset"].get<std::size_t>() + acc.value("byteOffset", std::size_t{0}), v.size() * 4);
  return v;
}

bool have_node_packages() {
  const fs::path n = source("tests/gltf/node/node_modules");
  return fs::exists(n / "three") && fs::exists(n / "gltf-validator") && std::system("node --version > /dev/null 2>&1") == 0;
}

int node(const std::string& script, const std::string& args, const TempDir& dir) {
  const std::string cmd = "cd " + q(dir.path()) + " && node " + q(source("tests/gltf/node") / script) + " " + args + " > node.txt 2>&1";
  const int code = std::system(cmd.c_str());
  INFO(mbi::test::slurp(dir / "node.txt"));
  CHECK(code == 0);
  return code;
}

}  // namespace

TEST_CASE("glTF from OBJ: UVs split at seams, groups and MTL materials, every frame", "[app][gltf]") {
  TempDir dir("gltf_obj");
  copy_crate(dir);
  fs::create_directories(dir / "out");
  // one run writes the glTF and a point cache of the same frames
  auto r = run_mbi(deform("twist.pc2", "--mesh model/crate.obj --mesh model/crate.obj --out out/anim.glb --out out/anim.pc2"),
                   dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  // what does not map is said once, by name
  CHECK(count(r.err, "warning") == 1);
  CHECK_THAT(r.err, Catch::Contains("MTL Ka, Ks, Ns, illum: no glTF PBR counterpart"));
  const auto [j, bin] = read_glb(dir / "out" / "anim.glb");
  // two primitives (body: wood, lid: glass); 5 sides x 4 corners, 2 shared across the one edge
  // whose UVs agree, + the lid's 4: 22 vertices for the crate's 8
  const auto& prims = j["meshes"][0]["primitives"];
  REQUIRE(prims.size() == 2);
  CHECK(j["accessors"][prims[0]["attributes"]["POSITION"].get<int>()]["count"] == 18);
  CHECK(j["accessors"][prims[1]["attributes"]["POSITION"].get<int>()]["count"] == 4);
  CHECK(j["accessors"][prims[1]["attributes"]["NORMAL"].get<int>()]["count"] == 4);
  CHECK(j["materials"][0]["name"] == "wood");
  CHECK(j["materials"][1]["alphaMode"] == "BLEND");
  // the texture lies outside the output's folder (which glTF readers refuse to look in): its
  // bytes are stored in the file; nothing is written beside the output
  CHECK(j["images"][0]["mimeType"] == "image/png");
  CHECK(!j["images"][0].contains("uri"));
  CHECK(bin.find(mbi::test::slurp(dir / "model" / "textures" / "checker.png")) != std::string::npos);
  CHECK(!fs::exists(dir / "out" / "textures"));
  CHECK(mbi::io::read_surface(dir / "out" / "anim.glb").V.rows() == 22);
  CHECK(mbi::io::read_pc2(dir / "out" / "anim.pc2").frames.at(0).rows() == 8);

  // one pose into a static glTF beside the model: the same, the texture named by a relative URI
  r = run_mbi(deform("twist_0001.txt", "--mesh model/crate.obj --out model/one.gltf"), dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(count(r.err, "warning") == 1);
  const nlohmann::json one = nlohmann::json::parse(mbi::test::slurp(dir / "model" / "one.gltf"));
  CHECK(one["materials"].size() == 2);
  CHECK(one["images"][0]["uri"] == "textures/checker.png");
  CHECK(one["meshes"][0]["primitives"][0].contains("/attributes/TEXCOORD_0"_json_pointer));
  // every split vertex has its OBJ vertex's position and deformed normal (the OBJ output's)
  REQUIRE(run_mbi(deform("twist_0001.txt", "--mesh model/crate.obj --out one.obj"), dir, "", dir.path()).code == 0);
  const mbi::io::SurfaceMesh split = mbi::io::read_surface(dir / "model" / "one.gltf"), plain = mbi::io::read_surface(dir / "one.obj");
  REQUIRE(split.V.rows() == 22);
  REQUIRE(split.N.rows() == 22);
  for (Eigen::Index i = 0; i < split.V.rows(); ++i) {
    Eigen::Index nearest = 0;
    (plain.V.rowwise() - split.V.row(i)).rowwise().norm().minCoeff(&nearest);
    CHECK((plain.V.row(nearest) - split.V.row(i)).cwiseAbs().maxCoeff() < 1e-6);
    CHECK((plain.N.row(nearest) - split.N.row(i)).cwiseAbs().maxCoeff() < 1e-6);
  }

  if (!have_node_packages()) mbi::test::skip("node or tests/gltf/node/node_modules missing (scripts/install-deps.sh test)");
  std::ofstream(dir / "materials.json") << R"({"wood": {"color": [0.8, 0.6, 0.4], "opacity": 1, "map": "stored"},
    "glass": {"color": [0.5, 0.7, 0.9], "opacity": 0.5, "map": null}})";
  node("validate.mjs", "out/anim.glb model/one.gltf", dir);
  node("obj_corners.mjs", "out/anim.glb model/crate.obj out/anim.pc2 materials.json", dir);
}

TEST_CASE("glTF from OBJ: Blender's importer reads the OBJ's UVs per corner", "[app][gltf][blender]") {
  if (std::system("blender --version > /dev/null 2>&1") != 0) mbi::test::skip("blender not installed");
  TempDir dir("gltf_blender");
  copy_crate(dir);
  auto r = run_mbi(deform("twist.pc2", "--mesh model/crate.obj --mesh model/crate.obj --out anim.glb --out anim.pc2"), dir, "",
                   dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string cmd = "cd " + q(dir.path()) + " && blender -b --factory-startup --python " +
                          q(source("tests/gltf/blender_uvs.py")) + " -- anim.glb model/crate.obj anim.pc2 > blender.txt 2>&1";
  const int code = std::system(cmd.c_str());
  INFO(mbi::test::slurp(dir / "blender.txt"));
  CHECK(code == 0);
  CHECK_THAT(mbi::test::slurp(dir / "blender.txt"), Catch::Contains("UVs as the OBJ's"));
}

TEST_CASE("glTF from PLY: vertex colours become COLOR_0", "[app][gltf]") {
  TempDir dir("gltf_ply");
  // a tetrahedron inside the box, colours as bytes
  std::ofstream(dir / "tet.ply") << "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
                                     "property double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                                     "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
                                     "0.2 0.2 0.3 255 0 0\n0.5 0.2 0.3 0 255 0\n0.2 0.5 0.3 0 0 255\n0.3 0.3 0.9 51 102 153\n"
                                     "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n";
  const auto r = run_mbi(deform("twist.pc2", "--mesh tet.ply --out tet.glb"), dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto [j, bin] = read_glb(dir / "tet.glb");
  const auto& attributes = j["meshes"][0]["primitives"][0]["attributes"];
  REQUIRE(attributes.contains("COLOR_0"));
  const std::vector<float> c = floats(j, bin, attributes["COLOR_0"].get<int>());
  const std::vector<float> want{1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1, 0.2f, 0.4f, 0.6f, 1};
  REQUIRE(c.size() == want.size());
  for (std::size_t i = 0; i < c.size(); ++i) CHECK(std::abs(c[i] - want[i]) < 1e-7);
  if (have_node_packages()) node("validate.mjs", "tet.glb", dir);
}

TEST_CASE("glTF from OBJ: a material library or texture outside the model's folder is not read", "[app][gltf]") {
  TempDir dir("gltf_obj_outside");
  copy_crate(dir);
  // a PNG beside the model's folder, named by the MTL; a second library beside it, named by the OBJ
  fs::copy_file(source("tests/gltf/data/textures/checker.png"), dir / "secret.png");
  std::ofstream(dir / "other.mtl") << "newmtl glass\nKd 0.1 0.1 0.1\n";
  std::string mtl = mbi::test::slurp(dir / "model" / "crate.mtl");
  mtl.replace(mtl.find("textures/checker.png"), std::strlen("textures/checker.png"), "../secret.png");
  std::ofstream(dir / "model" / "crate.mtl", std::ios::trunc) << mtl;
  std::string obj = mbi::test::slurp(dir / "model" / "crate.obj");
  obj.replace(obj.find("mtllib crate.mtl"), std::strlen("mtllib crate.mtl"), "mtllib ../other.mtl crate.mtl");
  std::ofstream(dir / "model" / "crate.obj", std::ios::trunc) << obj;
  fs::create_directories(dir / "out");
  const auto r = run_mbi(deform("twist.pc2", "--mesh model/crate.obj --out out/anim.glb"), dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK_THAT(r.err, Catch::Contains("other.mtl: material library outside the model's folder: not read") &&
                        Catch::Contains("secret.png: texture (map_Kd) outside the model's folder: left out"));
  const auto [j, bin] = read_glb(dir / "out" / "anim.glb");
  CHECK_FALSE(j.contains("images"));
  CHECK(bin.find("\x89PNG") == std::string::npos);
  // the glass material comes from crate.mtl, not from other.mtl
  const auto& glass = j["materials"][1];
  CHECK(glass["pbrMetallicRoughness"]["baseColorFactor"][0].get<double>() == Approx(0.5));
}
