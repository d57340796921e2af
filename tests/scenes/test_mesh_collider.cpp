// Mesh colliders in scene files: [[colliders]] shape = "mesh" names a closed triangle mesh
// (relative to the scene file's folder) that becomes a level set when the scene is loaded, placed
// by point and axes; each bad input is an error naming file, line and key; a ball dropped on the
// shipped staircase (scenes/steps.obj) comes to rest on a tread within 1e-3 of its diagonal.
#include <catch2/catch.hpp>

#include <mbi/interp/embed.hpp>
#include <mbi/scenes/models.hpp>

#include "common/files.hpp"
#include "common/sanitizers.hpp"
#include "common/temp_dir.hpp"
#include "scenes/contact_ball.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using namespace mbi::scenes;
using mbi::pipeline::ColliderShape;

namespace {

// The shipped staircase: treads at y = 0, 0.5 and 1 over x in [1.25, 3.75], [-1.25, 1.25] and
// [-3.75, -1.25], z in [-2, 2], the bottom at y = -0.5; 16 vertices, 28 triangles.
fs::path steps_obj() { return mbi::test::source_dir() / "scenes" / "steps.obj"; }
const double kStepsDiagonal = std::sqrt(7.5 * 7.5 + 1.5 * 1.5 + 4.0 * 4.0);

// The contact tests' ball (radius 0.5 about the origin) in a generated cage, over the steps
// placed by `collider` (the [[colliders]] entry's keys after shape).
std::string ball_over(const std::string& collider, int frames = 3, double damping = 2.0) {
  return "[dense]\npath = \"" + mbi::test::ball_file() + "\"\n[control]\ngenerate_vertices = 60\n"
         "[simulation]\ndt = 0.0333333\nframes = " + std::to_string(frames) + "\ngravity = [0, -9.81, 0]\n"
         "damping_mass = " + std::to_string(damping) + "\ncontact = \"surface\"\n"
         "[interpolation]\nmethod = \"bi\"\ngpu = \"off\"\n"
         "[[colliders]]\nshape = \"mesh\"\n" + collider;
}

// The scene's message, or "no error".
std::string error_of(const fs::path& file, const std::string& text) {
  std::ofstream(file) << text;
  try {
    load_scene(file);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

// "<file>:<line>" of the first line from [[colliders]] on that starts with `key`.
std::string at(const fs::path& file, const std::string& text, const std::string& key) {
  const std::size_t k = text.find("\n" + key, text.find("\n[[colliders]]"));
  return file.string() + ":" + std::to_string(std::count(text.begin(), text.begin() + static_cast<long>(k) + 1, '\n') + 1);
}

double collider_diagonal(const Eigen::MatrixXd& P) { return (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm(); }

}  // namespace

TEST_CASE("shape = \"mesh\": the file, relative to the scene's folder, is a level set once the scene is loaded",
          "[scenes][contact][mesh]") {
  mbi::test::TempDir dir("mesh-collider");
  fs::create_directories(dir / "meshes");
  fs::copy_file(steps_obj(), dir / "meshes" / "steps.obj");
  // turned a quarter about y (the file's x along -z) and lowered: the middle tread at y = -0.8
  const std::string placed = "path = \"meshes/steps.obj\"\npoint = [0, -1.3, 0]\n"
                             "axes = [[0, 0, -1], [0, 1, 0], [1, 0, 0]]\nfriction = 0.4\n"
                             "motion = { velocity = [0, -1, 0], start = 2 }\n";
  std::ofstream(dir / "s.toml") << ball_over(placed);
  const Scene sc = load_scene(dir / "s.toml");
  REQUIRE(sc.colliders.size() == 1);
  const mbi::pipeline::Collider& c = sc.colliders[0];
  CHECK(c.shape == ColliderShape::Mesh);
  REQUIRE(c.level_set);
  // the default voxel: the mesh's bounding-box diagonal / 128, a band of 3 voxels
  CHECK(c.level_set->voxel_size() == Approx(kStepsDiagonal / 128).epsilon(1e-12));
  CHECK(c.level_set->band() == Approx(3 * kStepsDiagonal / 128).epsilon(1e-12));
  CHECK(c.friction == 0.4);
  CHECK(c.point == Eigen::Vector3d(0, -1.3, 0));
  CHECK(c.axes(2, 0) == -1.0);  // the first axis is the column [0, 0, -1]
  CHECK(c.motion.velocity == Eigen::Vector3d(0, -1, 0));
  CHECK(c.motion.start == 2.0);
  // 0.1 m above the middle tread and above the lowest (file x = 2.5, placed at z = -2.5): flat
  // faces more than a voxel from an edge, where the level set is the plane's distance to float
  // round-off
  CHECK(mbi::pipeline::signed_distance(c, {0, -0.7, 0}, 0).value == Approx(0.1).margin(1e-5));
  CHECK(mbi::pipeline::signed_distance(c, {0, -1.2, -2.5}, 0).value == Approx(0.1).margin(1e-5));
  CHECK(mbi::pipeline::signed_distance(c, {0, -1.2, 2.5}, 0).value < 0);  // inside the upper step
  // voxel_size and band_voxels given
  std::ofstream(dir / "fine.toml") << ball_over("path = \"meshes/steps.obj\"\nvoxel_size = 0.05\nband_voxels = 2\n");
  const Scene fine = load_scene(dir / "fine.toml");
  CHECK(fine.colliders[0].level_set->voxel_size() == 0.05);
  CHECK(fine.colliders[0].level_set->band() == Approx(0.1).epsilon(1e-12));
  // parse_scene reads nothing: the collider is placed, its file named; read_collider_meshes reads it
  Scene parsed = parse_scene(ball_over(placed), dir / "s.toml");
  CHECK_FALSE(parsed.colliders[0].level_set);
  REQUIRE(parsed.collider_meshes.size() == 1);
  CHECK(parsed.collider_meshes[0].path == "meshes/steps.obj");
  read_collider_meshes(parsed);
  REQUIRE(parsed.colliders[0].level_set);
  CHECK(parsed.colliders[0].level_set->active_voxels() == c.level_set->active_voxels());
}

TEST_CASE("shape = \"mesh\": each bad input is an error naming file, line and key", "[scenes][contact][mesh]") {
  mbi::test::TempDir dir("mesh-collider-errors");
  const fs::path s = dir / "s.toml";
  auto contains = [](const std::string& what) { return Catch::Matchers::Contains(what); };
  auto check = [&](const std::string& keys, const std::string& line_key, const std::string& message) {
    const std::string text = ball_over(keys);
    INFO(keys);
    CHECK_THAT(error_of(s, text), contains(at(s, text, line_key) + ": colliders[0]" + message));
  };
  const std::string steps = "path = \"" + steps_obj().string() + "\"\n";
  check("friction = 0\n", "[[colliders]]", ".path: missing");
  check("path = \"\"\n", "path", ".path: must name a file");
  check("path = \"nothere.obj\"\n", "path", ".path: ");
  CHECK_THAT(error_of(s, ball_over("path = \"nothere.obj\"\n")), contains("nothere.obj"));
  std::ofstream(dir / "notes.txt") << "not a mesh\n";
  check("path = \"notes.txt\"\n", "path", ".path: ");
  // a staircase with one triangle left out: two edges are used once
  {
    std::ifstream in(steps_obj());
    std::ofstream out(dir / "open.obj");
    std::string line, last;
    while (std::getline(in, line)) {
      if (!last.empty()) out << last << "\n";
      last = line;
    }
  }
  check("path = \"open.obj\"\n", "path", ".path: " + (dir / "open.obj").string());
  CHECK_THAT(error_of(s, ball_over("path = \"open.obj\"\n")), contains("the mesh is not closed: 3 boundary edges"));
  check(steps + "voxel_size = -1\n", "voxel_size", ".voxel_size: value -1 out of range");
  check(steps + "voxel_size = 0\n", "voxel_size", ".voxel_size: value 0 out of range");
  check(steps + "voxel_size = 1e-4\n", "voxel_size", ".voxel_size: ");
  CHECK_THAT(error_of(s, ball_over(steps + "voxel_size = 1e-4\n")), contains("too small for the mesh"));
  check(steps + "voxel_size = \"fine\"\n", "voxel_size", ".voxel_size: expected a number");
  check(steps + "band_voxels = 0.5\n", "band_voxels", ".band_voxels: value 0.5 out of range");
  check(steps + "radius = 1\n", "radius", ".radius: unknown key");
  check(steps + "axes = [[1, 0, 0], [1, 0, 0], [0, 0, 1]]\n", "[[colliders]]", ": axes must be a rotation");
  check(steps + "point = [0, 0]\n", "point", ".point: expected 3 numbers");
}

TEST_CASE("shape = \"mesh\": a ball dropped on the steps rests on a tread within 1e-3 of its diagonal",
          "[scenes][contact][mesh]") {
  // The 0.3 m fall takes 8 frames; the bounce then decays by about 2.3 a period of 10 frames.
  // The sanitizers make each frame slow: damped harder, on the tread sooner, and still creeping
  // at 25 frames (the release pass checks the speed).
  const bool quick = mbi::test::kSanitized;
  const int frames = quick ? 25 : 100, settled = quick ? 15 : 40, still = quick ? frames + 1 : 90;
  // the shipped steps lowered so that the middle tread (y = 0.5 in the file) is at y = -0.8
  const std::string text = ball_over("path = \"" + steps_obj().string() + "\"\npoint = [0, -1.3, 0]\n", frames,
                                     quick ? 8.0 : 2.0);
  // parse_scene alone: make_pipeline reads the mesh the scene names
  const Scene sc = parse_scene(text, "ball.toml");
  Scene loaded = sc;
  read_collider_meshes(loaded);
  const mbi::pipeline::Collider& steps = loaded.colliders.at(0);
  const SceneModels m = load_models(sc);
  mbi::pipeline::FramePipeline pipe = make_pipeline(sc, m, mbi::interp::embed(m.U, m.T, m.dense.V));
  const double diag = collider_diagonal(m.dense.V), dt = sc.simulation.parameters.dt;
  Eigen::MatrixXd before = m.dense.V;
  for (int k = 1; k <= frames; ++k) {
    INFO("frame " << k);
    REQUIRE(pipe.step().ok);
    const Eigen::MatrixXd& P = pipe.positions();
    double lowest = HUGE_VAL;  // the dense points' least distance to the steps' level set
    for (Eigen::Index i = 0; i < P.rows(); ++i)
      lowest = std::min(lowest, mbi::pipeline::signed_distance(steps, P.row(i).transpose(), k * dt).value);
    CHECK(lowest >= -1e-3 * diag);  // at every frame, the impact included
    if (k >= settled) {
      CHECK(lowest <= 1e-3 * diag);
      // on the tread itself (a flat face: the level set is its plane there), centred above it
      CHECK(std::abs(P.col(1).minCoeff() - -0.8) <= 1e-3 * diag);
      CHECK(std::abs(P.col(0).mean()) < 0.1);
    }
    // at rest: no point moves faster than 1e-3 diagonals a second (2.4 m/s at the impact)
    if (k >= still) CHECK((P - before).rowwise().norm().maxCoeff() / dt <= 1e-3 * diag);
    before = P;
  }
}
