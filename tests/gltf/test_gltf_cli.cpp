// The multi-part glTF fixture (written by three.js, tests/gltf/data/README.md) through mbi cage,
// mbi run (a scene writing mesh.glb) and mbi deform (the run's control trajectory into an
// animated .glb); then, where the node packages are installed (tests/gltf/node), the Khronos
// validator finds no error and three.js plays every frame back with our positions, materials
// and UVs.
#include <mbi/io/io.hpp>

#include "common/files.hpp"
#include "common/run_mbi.hpp"
#include "common/skip.hpp"

#include <catch2/catch.hpp>

#include <cstdlib>
#include <fstream>

namespace fs = std::filesystem;
using mbi::test::q;
using mbi::test::run_mbi;
using mbi::test::TempDir;

namespace {

fs::path node_dir() { return mbi::test::source_dir() / "tests" / "gltf" / "node"; }

const char* kScene = R"(name = "toy"
[dense]
path = "parts.glb"
[control]
path = "cage.node"
[material]
young = 2e4
poisson = 0.4
density = 1000
[simulation]
dt = 0.04
frames = 4
gravity = [0, -9.81, 0]
[[constraints]]
type = "fixed"
select = { box_relative = { min = [0, 0.9, 0], max = [1, 1, 1] } }
[interpolation]
gpu = "off"
[output]
every = 1
mesh_format = "glb"
image = false
)";

// cage, run and deform in `dir`: run/mesh.glb with run/dense.pc2, anim.glb with anim.pc2.
void run_pipeline(const TempDir& dir) {
  fs::copy_file(mbi::test::source_dir() / "tests" / "gltf" / "data" / "parts.glb", dir / "parts.glb");
  std::ofstream(dir / "toy.toml") << kScene;
  auto r = run_mbi("cage parts.glb -n 60 -o cage", dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  r = run_mbi("run toy.toml --out run --quiet", dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  for (const char* out : {"anim.glb", "anim.pc2"}) {
    r = run_mbi("deform --control cage --deformed 'run/control_%04d.vtk' --mesh parts.glb --out " + std::string(out), dir, "",
                dir.path());
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK_THAT(r.out, Catch::Contains("frames:  5 of 5"));
  }
}

void replace(std::string& s, const std::string& from, const std::string& to) {
  const std::size_t at = s.find(from);
  REQUIRE(at != std::string::npos);
  s.replace(at, from.size(), to);
}

bool have_node_packages() {
  return fs::exists(node_dir() / "node_modules" / "three") && fs::exists(node_dir() / "node_modules" / "gltf-validator") &&
         std::system("node --version > /dev/null 2>&1") == 0;
}

int node(const std::string& script, const std::string& args, const TempDir& dir) {
  const std::string cmd = "cd " + q(dir.path()) + " && node " + q(node_dir() / script) + " " + args + " > node.txt 2>&1";
  const int code = std::system(cmd.c_str());
  INFO(mbi::test::slurp(dir / "node.txt"));
  CHECK(code == 0);
  return code;
}

}  // namespace

TEST_CASE("glTF: the fixture through cage, run and deform keeps its parts", "[app][gltf]") {
  TempDir dir("gltf_cli");
  run_pipeline(dir);
  const mbi::io::SurfaceMesh in = mbi::io::read_surface(dir / "parts.glb");
  const mbi::io::PointCache cache = mbi::io::read_pc2(dir / "anim.pc2");
  REQUIRE(cache.frames.size() == 5);
  // an animated glTF reads back as its first frame, with the input's faces
  for (const char* file : {"anim.glb", "run/mesh.glb"}) {
    const mbi::io::SurfaceMesh first = mbi::io::read_surface(dir / file);
    CHECK(first.F == in.F);
    CHECK((first.V - cache.frames[0]).cwiseAbs().maxCoeff() < 1e-5);
  }
  // one frame: a static glTF
  const auto r = run_mbi("deform --control cage --deformed run/control_0004.vtk --mesh parts.glb --out last.gltf", dir, "",
                         dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK((mbi::io::read_surface(dir / "last.gltf").V - cache.frames[4]).cwiseAbs().maxCoeff() < 1e-5);
}

TEST_CASE("glTF: the Khronos validator and three.js read our files back", "[app][gltf][node]") {
  if (!have_node_packages()) mbi::test::skip("node or tests/gltf/node/node_modules missing (scripts/install-deps.sh test)");
  TempDir dir("gltf_node");
  run_pipeline(dir);
  REQUIRE(run_mbi("deform --control cage --deformed cage.node --mesh parts.glb --out rest.gltf", dir, "", dir.path()).code == 0);
  node("validate.mjs", "parts.glb anim.glb run/mesh.glb rest.gltf", dir);
  node("playback.mjs", "anim.glb anim.pc2 parts.glb", dir);
  node("playback.mjs", "run/mesh.glb run/dense.pc2 parts.glb", dir);
}

TEST_CASE("several dense meshes: one cage around all, each --out as that mesh deformed alone", "[app][gltf]") {
  TempDir dir("gltf_parts");
  run_pipeline(dir);
  const fs::path sphere = mbi::test::source_dir() / "tests" / "data" / "vtu" / "sphere.obj";
  auto r = run_mbi("cage parts.glb " + q(sphere) + " -n 80 -o two", dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  r = run_mbi("deform --control two --deformed two.node --mesh parts.glb --mesh " + q(sphere) +
                  " --out both.glb --out both.obj",
              dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  REQUIRE(run_mbi("deform --control two --deformed two.node --mesh parts.glb --out one.glb", dir, "", dir.path()).code == 0);
  REQUIRE(run_mbi("deform --control two --deformed two.node --mesh " + q(sphere) + " --out one.obj", dir, "", dir.path()).code == 0);
  CHECK(mbi::test::slurp(dir / "both.obj") == mbi::test::slurp(dir / "one.obj"));
  CHECK(mbi::io::read_surface(dir / "both.glb").V == mbi::io::read_surface(dir / "one.glb").V);
  // a trajectory into one output a mesh: a glTF and numbered OBJ files
  r = run_mbi("deform --control cage --deformed 'run/control_%04d.vtk' --mesh parts.glb --mesh parts.glb --out a.glb "
              "--out 'b_%02d.obj'",
              dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(fs::exists(dir / "b_04.obj"));
  CHECK(mbi::io::read_surface(dir / "a.glb").V == mbi::io::read_surface(dir / "anim.glb").V);
  r = run_mbi("deform --control cage --deformed cage.node --mesh parts.glb --mesh parts.glb --out x.obj", dir, "", dir.path());
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("2 --mesh but 1 --out"));
}

TEST_CASE("a scene of several [[dense]] models writes each on its own, as mbi deform does", "[app][gltf]") {
  TempDir dir("gltf_scene_parts");
  run_pipeline(dir);
  fs::copy_file(mbi::test::source_dir() / "tests" / "data" / "vtu" / "sphere.obj", dir / "sphere.obj");
  REQUIRE(run_mbi("cage parts.glb sphere.obj -n 80 -o two", dir, "", dir.path()).code == 0);
  std::string scene = kScene;
  replace(scene, "[dense]\npath = \"parts.glb\"", "[[dense]]\npath = \"parts.glb\"\n[[dense]]\npath = \"sphere.obj\"");
  replace(scene, "cage.node", "two.node");
  std::ofstream(dir / "two.toml") << scene;
  auto r = run_mbi("run two.toml --out run2 --quiet", dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  r = run_mbi("deform --control two --deformed 'run2/control_%04d.vtk' --mesh parts.glb --mesh sphere.obj --out p.glb "
              "--out 's_%04d.obj' --alpha 0.1",
              dir, "", dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK((mbi::io::read_surface(dir / "run2" / "mesh1.glb").V - mbi::io::read_surface(dir / "p.glb").V).cwiseAbs().maxCoeff() < 1e-6);
  CHECK(fs::exists(dir / "run2" / "mesh2.glb"));
  CHECK_FALSE(fs::exists(dir / "run2" / "mesh.glb"));
  // a [[dense]] entry other than the first is a file
  replace(scene, "path = \"sphere.obj\"", "builtin = \"cylinder\"");
  std::ofstream(dir / "bad.toml") << scene;
  r = run_mbi("run bad.toml --out run3 --quiet", dir, "", dir.path());
  CHECK(r.code != 0);
  CHECK_THAT(r.err, Catch::Contains("several dense models are files"));
}
