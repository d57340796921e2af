// The headless runner: every shipped scene runs a few frames, its metrics parse, and
// modified-BI's mean face discontinuity is below BI's; outputs are complete and protected.
#include <catch2/catch.hpp>

#include <mbi/io/io.hpp>
#include <mbi/generate/procedural.hpp>
#include <mbi/scenes/runner.hpp>

#include "common/temp_dir.hpp"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>

namespace fs = std::filesystem;
using namespace mbi::scenes;
using namespace mbi::io;
using namespace mbi::generate;

namespace {

fs::path source_dir() {
  const char* s = std::getenv("MBI_SOURCE_DIR");
  REQUIRE(s != nullptr);
  return s;
}

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  REQUIRE(in.good());
  return nlohmann::json::parse(in);
}

void check_run(const std::string& scene_name, int frames) {
  mbi::test::TempDir dir("run");
  const Scene sc = load_scene(source_dir() / "scenes" / (scene_name + ".toml"));
  RunOptions o;
  o.out_dir = dir / "out";
  o.frames = frames;
  const RunResult r = run_scene(sc, o);
  INFO(scene_name);
  REQUIRE_FALSE(r.failed);
  CHECK(r.frames == frames);
  const nlohmann::json m = read_json(o.out_dir / "metrics.json");
  CHECK(m["frames"].size() == static_cast<size_t>(frames + 1));
  CHECK(m["frames_completed"] == frames);
  CHECK(m["failure"].is_null());
  CHECK(m["outside_points"] == 0);
  for (const auto& f : m["frames"]) {
    CHECK(f["solve_ms"].get<double>() >= 0);
    CHECK(f["interp_ms"].get<double>() >= 0);
  }
  const auto& last = m["frames"].back()["disc"];
  const double bi = last["bi"]["mean"], mbi_mean = last["modified_bi"]["mean"];
  CHECK(bi > 0);
  CHECK(mbi_mean < bi);
  // outputs of the last frame and the point cache
  if (sc.output.mesh_format != MeshFormat::None)
    CHECK(fs::exists(frame_path(o.out_dir / "mesh", frames, std::string(".") + format_name(sc.output.mesh_format))));
  CHECK(fs::exists(frame_path(o.out_dir / "frame", frames, ".png")));
  CHECK(fs::exists(frame_path(o.out_dir / "control", frames, ".vtk")));
  const PointCache pc = read_pc2(o.out_dir / "dense.pc2");
  CHECK(pc.frames.size() == static_cast<size_t>(frames + 1));
  CHECK(static_cast<long>(pc.frames.front().rows()) == static_cast<long>(m["dense_vertices"]));
  // no temporary files left behind
  for (const auto& e : fs::directory_iterator(o.out_dir))
    CHECK(e.path().filename().string().find(".tmp") == std::string::npos);
}

}  // namespace

TEST_CASE("scene twist-bar runs", "[runner]") { check_run("twist-bar", 4); }
TEST_CASE("scene cantilever runs", "[runner]") { check_run("cantilever", 4); }
TEST_CASE("scene poke runs", "[runner]") { check_run("poke", 4); }
TEST_CASE("scene drag runs", "[runner]") { check_run("drag", 4); }
TEST_CASE("scene image-warp runs", "[runner]") { check_run("image-warp", 3); }
TEST_CASE("scene large runs", "[runner]") { check_run("large", 2); }

TEST_CASE("outputs are not overwritten without force", "[runner]") {
  mbi::test::TempDir dir("run");
  const Scene sc = load_scene(source_dir() / "scenes" / "twist-bar.toml");
  RunOptions o;
  o.out_dir = dir / "out";
  o.frames = 1;
  run_scene(sc, o);
  const auto stamp = fs::last_write_time(o.out_dir / "metrics.json");
  CHECK_THROWS_WITH(run_scene(sc, o), Catch::Contains("use --force"));
  CHECK(fs::last_write_time(o.out_dir / "metrics.json") == stamp);
  o.force = true;
  CHECK_NOTHROW(run_scene(sc, o));
}

TEST_CASE("a mesh override replaces the dense model and method bi gives BI output", "[runner]") {
  mbi::test::TempDir dir("run");
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  cylinder_surface(0.3, 1.5, 24, 10, 3, V, F);
  write_surface(dir / "user.obj", V, F);
  const Scene sc = load_scene(source_dir() / "scenes" / "poke.toml");
  RunOptions o;
  o.out_dir = dir / "out";
  o.frames = 2;
  o.mesh = dir / "user.obj";
  o.method = mbi::pipeline::Method::BI;
  const RunResult r = run_scene(sc, o);
  REQUIRE_FALSE(r.failed);
  const nlohmann::json m = read_json(o.out_dir / "metrics.json");
  CHECK(m["dense_vertices"] == V.rows());
  CHECK(m["method"] == "bi");
  const SurfaceMesh out = read_surface(frame_path(o.out_dir / "mesh", 0, ".obj"));
  CHECK(out.V.rows() == V.rows());
  CHECK((out.V - V).cwiseAbs().maxCoeff() < 1e-9);  // frame 0 is the rest pose
}

TEST_CASE("a failing simulation step stops the run and keeps what was written", "[runner]") {
  mbi::test::TempDir dir("run");
  // an absurd force on a soft bar: the simulator's energy guard fails step 3
  std::ofstream(dir / "fail.toml") << R"(
[dense]
builtin = "paper-bar"
[control]
builtin = "paper-bar"
[material]
young = 1000
[simulation]
frames = 20
[[constraints]]
select = { box_relative = { min = [0, 0, 0], max = [1, 1, 0] } }
[[pokes]]
first = 3
last = 20
point = [0.0, 0.0, 6.0]
force = [1e15, 0, 0]
[output]
every = 2
)";
  const Scene sc = load_scene(dir / "fail.toml");
  RunOptions o;
  o.out_dir = dir / "out";
  const RunResult r = run_scene(sc, o);
  CHECK(r.failed);
  CHECK_THAT(r.message, Catch::Contains("step 3"));
  CHECK(r.frames == 2);
  const nlohmann::json m = read_json(o.out_dir / "metrics.json");
  CHECK(m["frames_completed"] == 2);
  CHECK_THAT(m["failure"].get<std::string>(), Catch::Contains("step 3"));
  CHECK(read_pc2(o.out_dir / "dense.pc2").frames.size() == 3);  // frames 0, 1, 2
  const SurfaceMesh last = read_surface(frame_path(o.out_dir / "mesh", 2, ".obj"));
  CHECK(last.V.allFinite());
  CHECK_FALSE(fs::exists(frame_path(o.out_dir / "mesh", 4, ".obj")));
}

TEST_CASE("dense.subdivide densifies with Loop subdivision", "[runner]") {
  mbi::test::TempDir dir("run");
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  cylinder_surface(0.4, 2.0, 16, 6, 2, V, F);
  write_surface(dir / "c.obj", V, F);
  std::ofstream(dir / "s.toml") << "[dense]\npath = \"c.obj\"\nsubdivide = 1\n[control]\nbuiltin = \"box\"\n"
                                   "cells = [2, 2, 4]\n[simulation]\nframes = 1\n";
  const SceneModels m = load_models(load_scene(dir / "s.toml"));
  // Loop: one new vertex per edge; a closed triangle mesh has 3F/2 edges
  CHECK(m.dense.V.rows() == V.rows() + 3 * F.rows() / 2);
  CHECK(m.dense.F.rows() == 4 * F.rows());
  // the smoothed surface shrinks slightly but stays inside the (padded) box control mesh
  RunOptions o;
  o.out_dir = dir / "out";
  const RunResult r = run_scene(load_scene(dir / "s.toml"), o);
  CHECK_FALSE(r.failed);
  CHECK(r.outside_points == 0);
}

TEST_CASE("image-warp with a user PNG writes warped pictures of its size", "[runner]") {
  mbi::test::TempDir dir("run");
  write_png(dir / "pic.png", test_pattern(120, 80));
  std::ofstream(dir / "w.toml") << R"(
mode = "drag"
[dense]
builtin = "image-grid"
image = "pic.png"
grid = 24
[control]
builtin = "grid-2d"
cells = [3, 2]
[[drags]]
select = { box_relative = { min = [0, 0, 0], max = [1, 0, 0] } }
keys = [[0, 0, 0]]
[[drags]]
near = [60, 80]
keys = [[0, 0, 0], [2, 10, 15]]
[simulation]
frames = 2
[interpolation]
compare_pinned = true
[output]
mesh_format = "none"
)";
  RunOptions o;
  o.out_dir = dir / "out";
  const RunResult r = run_scene(load_scene(dir / "w.toml"), o);
  REQUIRE_FALSE(r.failed);
  const Image img = read_png(frame_path(o.out_dir / "frame", 2, ".png"));
  // three panels (BI, modified-BI, pinned) of 1.5 x the picture, 8-pixel gaps
  CHECK(img.width == 3 * 180 + 2 * 8);
  CHECK(img.height == 120);
}
