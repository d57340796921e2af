// Scene files: every shipped scene parses; bad files give one-line errors naming file, line, key.
#include <catch2/catch.hpp>
#include <common/files.hpp>

#include <mbi/scenes/scene.hpp>

#include "common/temp_dir.hpp"

#include <cstdlib>
#include <fstream>

namespace fs = std::filesystem;
using mbi::scenes::load_scene;

namespace {

fs::path write(const mbi::test::TempDir& dir, const std::string& text) {
  const fs::path p = dir / "scene.toml";
  std::ofstream(p) << text;
  return p;
}

const char* minimal = R"(
[dense]
builtin = "paper-bar"
[control]
builtin = "paper-bar"
)";

std::string error_of(const fs::path& p) {
  try {
    load_scene(p);
  } catch (const mbi::scenes::Error& e) {
    return e.what();
  }
  FAIL("no error for " << p);
  return {};
}

}  // namespace

TEST_CASE("every shipped scene parses", "[scene]") {
  int n = 0;
  for (const auto& entry : fs::directory_iterator(mbi::test::source_dir() / "scenes")) {
    if (entry.path().extension() != ".toml") continue;
    INFO(entry.path());
    const auto sc = load_scene(entry.path());
    CHECK(!sc.name.empty());
    ++n;
  }
  CHECK(n >= 6);
}

TEST_CASE("defaults are applied", "[scene]") {
  mbi::test::TempDir dir("scene");
  const auto sc = load_scene(write(dir, minimal));
  CHECK(sc.mode == mbi::scenes::Mode::Simulate);
  CHECK(sc.interpolation.method == mbi::pipeline::Method::ModifiedBI);
  CHECK(sc.simulation.frames == 120);
  CHECK(sc.material.poisson_ratio == Approx(0.45));
  CHECK(sc.name == "scene");
}

TEST_CASE("simulation and motion keys fill the simulator's own parameters", "[scene]") {
  mbi::test::TempDir dir("scene");
  const auto plain = load_scene(write(dir, minimal));
  CHECK(plain.simulation.parameters.dt == Approx(1.0 / 30.0));
  CHECK(plain.simulation.parameters.gravity.norm() == 0.0);
  CHECK_FALSE(plain.simulation.parameters.ground);
  const auto sc = load_scene(write(dir, std::string(minimal) +
                                            "[simulation]\ndt = 0.01\nsubsteps = 3\ndamping_mass = 0.5\n"
                                            "damping_stiffness = 0.02\nground = -1.5\n"
                                            "[[constraints]]\ntype = \"kinematic\"\nselect = { indices = [0] }\n"
                                            "motion = { twist_axis = [1, 0, 0], twist_center = [0, 2, 0], "
                                            "twist_rate = 0.25, stop = 4 }\n"));
  const mbi::sim::Parameters& p = sc.simulation.parameters;
  CHECK(p.dt == 0.01);
  CHECK(p.substeps == 3);
  CHECK(p.mass_damping == 0.5);
  CHECK(p.stiffness_damping == 0.02);
  CHECK(p.ground);
  CHECK(p.ground_plane.offset == -1.5);
  CHECK(p.ground_plane.normal == Eigen::Vector3d::UnitY());
  REQUIRE(sc.constraints.size() == 1);
  const mbi::sim::RigidMotion& m = sc.constraints[0].motion;
  CHECK(m.axis == Eigen::Vector3d::UnitX());
  CHECK(m.center == Eigen::Vector3d(0, 2, 0));
  CHECK(m.angular_velocity == 0.25);
  CHECK(m.start == 0.0);
  CHECK(m.stop == 4.0);
}

TEST_CASE("one name table per enum: names round-trip, unknown names list the choices", "[scene]") {
  using namespace mbi::scenes;
  for (const std::string& n : kModeNames.names()) CHECK(mode_name(*kModeNames.find(n)) == n);
  for (const std::string& n : kGpuUseNames.names()) CHECK(gpu_name(*kGpuUseNames.find(n)) == n);
  for (const std::string& n : kMeshFormatNames.names()) CHECK(format_name(*kMeshFormatNames.find(n)) == n);
  CHECK(std::string(builtin_name(DenseBuiltin::None)).empty());
  CHECK(kControlBuiltinNames.joined() == "paper-bar, box, grid-2d");
  CHECK_FALSE(kHandleModeNames.find("Hard").has_value());
  CHECK_THROWS_WITH(kGpuUseNames.parse("maybe", "--gpu"),
                    "--gpu: unknown value \"maybe\" (expected one of: auto, on, off)");
  mbi::test::TempDir dir("scene");
  CHECK_THAT(error_of(write(dir, std::string(minimal) + "[interpolation]\ngpu = \"maybe\"\n")),
             Catch::EndsWith("interpolation.gpu: unknown value \"maybe\" (expected one of: auto, on, off)"));
}

TEST_CASE("unknown keys are errors naming file, line and key", "[scene]") {
  mbi::test::TempDir dir("scene");
  const std::string msg = error_of(write(dir, std::string(minimal) + "[material]\nyoung = 1e5\nyuong = 3\n"));
  CHECK_THAT(msg, Catch::Contains("scene.toml:8:"));
  CHECK_THAT(msg, Catch::Contains("material.yuong"));
  CHECK_THAT(msg, Catch::Contains("unknown key"));
  // unknown top-level key and unknown nested key in an array of tables
  CHECK_THAT(error_of(write(dir, std::string(minimal) + "colour = 1\n")), Catch::Contains("colour: unknown key"));
  CHECK_THAT(error_of(write(dir, std::string(minimal) +
                                     "[[constraints]]\ntype = \"fixed\"\nselect = { box_relative = {min=[0,0,0], max=[1,1,0]}, bogus = 1 }\n")),
             Catch::Contains("constraints[0].select.bogus"));
}

TEST_CASE("wrong types and out-of-range values are errors naming the key", "[scene]") {
  mbi::test::TempDir dir("scene");
  const std::string base(minimal);
  auto err = [&](const std::string& extra) { return error_of(write(dir, base + extra)); };
  CHECK_THAT(err("[material]\nyoung = \"soft\"\n"), Catch::Contains("material.young: expected a number"));
  CHECK_THAT(err("[material]\npoisson = 0.5\n"), Catch::Contains("material.poisson"));
  CHECK_THAT(err("[material]\nyoung = -1.0\n"), Catch::Contains("material.young"));
  CHECK_THAT(err("[simulation]\nframes = 2.5\n"), Catch::Contains("simulation.frames: expected an integer"));
  CHECK_THAT(err("[simulation]\ndt = 0\n"), Catch::Contains("simulation.dt"));
  CHECK_THAT(err("[simulation]\ngravity = [0, 1]\n"), Catch::Contains("simulation.gravity"));
  CHECK_THAT(err("[interpolation]\nalpha = 0\n"), Catch::Contains("interpolation.alpha"));
  CHECK_THAT(err("[interpolation]\nalpha = -0.1\n"), Catch::Contains("interpolation.alpha"));
  CHECK_THAT(err("[interpolation]\nmethod = \"cubic\"\n"), Catch::Contains("interpolation.method: unknown value"));
  CHECK_THAT(err("[interpolation]\nmethod = \"cubic\"\n"), Catch::Contains("phong"));
  CHECK_THAT(err("[[pokes]]\nfirst = 3\nlast = 1\nat = [0.5, 0.5, 0.5]\nforce = [1, 0, 0]\n"),
             Catch::Contains("pokes[0].last"));
  CHECK_THAT(err("[[pokes]]\nat = [0.5, 0.5, 0.5]\n"), Catch::Contains("exactly one of force or target"));
  CHECK_THAT(err("[output]\nmesh_format = \"fbx\"\n"), Catch::Contains("output.mesh_format"));
}

TEST_CASE("structural errors", "[scene]") {
  mbi::test::TempDir dir("scene");
  CHECK_THAT(error_of(write(dir, "[control]\nbuiltin = \"box\"\n")), Catch::Contains("missing table [dense]"));
  CHECK_THAT(error_of(write(dir, "[dense]\nbuiltin = \"paper-bar\"\npath = \"x.obj\"\n[control]\nbuiltin=\"box\"\n")),
             Catch::Contains("exactly one of path or builtin"));
  CHECK_THAT(error_of(write(dir, "[dense\nbuiltin = 1\n")), Catch::Contains("scene.toml:1: syntax error"));
  CHECK_THAT(error_of(dir / "missing.toml"), Catch::Contains("missing.toml: no such scene file"));
  CHECK_THAT(error_of(write(dir, "mode = \"drag\"\n" + std::string(minimal))), Catch::Contains("at least one [[drags]]"));
}

TEST_CASE("a poke without first/last acts over the whole run, keys a drag scene would ignore are errors",
          "[scene]") {
  mbi::test::TempDir dir("scene");
  const std::string poke = "[[pokes]]\nat = [0.5, 0.5, 0.5]\nforce = [1, 0, 0]\n";
  const auto sc = load_scene(write(dir, std::string(minimal) + poke));
  REQUIRE(sc.pokes.size() == 1);
  CHECK(sc.pokes[0].first == 0);
  CHECK(sc.pokes[0].last >= 1000000);  // any run's last frame
  const auto from = load_scene(write(dir, std::string(minimal) + poke + "first = 5\n"));
  CHECK(from.pokes[0].first == 5);
  CHECK(from.pokes[0].last >= 1000000);
  const std::string drag = "mode = \"drag\"\n" + std::string(minimal) + "[[drags]]\nvertex = 0\nkeys = [[0, 0, 0, 0]]\n";
  CHECK_THAT(error_of(write(dir, drag + poke)),
             Catch::Contains("scene.toml:10: pokes: only simulate scenes") && Catch::Contains("[[drags]] alone"));
  CHECK_THAT(error_of(write(dir, drag + "[[constraints]]\ntype = \"fixed\"\nselect = { indices = [0] }\n")),
             Catch::Contains("constraints: only simulate scenes"));
}

TEST_CASE("node selections", "[scene]") {
  Eigen::MatrixXd U(5, 3);
  U << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  mbi::scenes::Selection s;
  s.box_relative = std::make_pair(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 0));
  CHECK(mbi::scenes::select_nodes(s, U) == std::vector<int>{0, 1, 2});
  s = {};
  s.half_space = std::make_pair(Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(0, 0, 1));
  CHECK(mbi::scenes::select_nodes(s, U) == std::vector<int>{3, 4});
  s = {};
  s.indices = {4, 1};
  CHECK(mbi::scenes::select_nodes(s, U) == std::vector<int>{1, 4});
  s.indices = {5};
  CHECK_THROWS_WITH(mbi::scenes::select_nodes(s, U), Catch::Contains("node 5 out of range"));
  s = {};
  s.box = std::make_pair(Eigen::Vector3d::Constant(5), Eigen::Vector3d::Constant(6));
  CHECK_THROWS_WITH(mbi::scenes::select_nodes(s, U), Catch::Contains("selects no control node"));
}
