// Contact in scenes: `contact = "surface"` rests the dense surface on the ground within 1e-3 of
// its diagonal through `mbi run`'s runner for every method, while `contact = "control"` (the
// negative control) leaves the cage's margin under it; the `ground` key of a control scene keeps
// its meaning (the same steps as the simulator's own ground plane); [[colliders]] and the
// contact keys are checked, errors naming the key and the collider.
#include <catch2/catch.hpp>

#include <mbi/interp/embed.hpp>
#include <mbi/io/io.hpp>
#include <mbi/pipeline/driver.hpp>
#include <mbi/scenes/models.hpp>
#include <mbi/scenes/runner.hpp>

#include "common/sanitizers.hpp"
#include "common/temp_dir.hpp"
#include "scenes/contact_ball.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace mbi::scenes;
using mbi::pipeline::ColliderShape;
using mbi::pipeline::ContactMode;
using mbi::test::ball_file;

namespace {

// The ball in a generated cage with a margin, dropped from 0.3 m onto a ground at y = -0.8 (its
// bottom is at y = -0.5), damped to rest.
std::string ball_scene(const std::string& contact, const std::string& method, int frames, double damping = 2.0) {
  return "[dense]\npath = \"" + ball_file() + "\"\n[control]\ngenerate_vertices = 60\n"
         "[simulation]\ndt = 0.0333333\nframes = " + std::to_string(frames) +
         "\ngravity = [0, -9.81, 0]\ndamping_mass = " + std::to_string(damping) + "\nground = -0.8\ncontact = \"" + contact +
         "\"\n[interpolation]\nmethod = \"" + method + "\"\ngpu = \"off\"\n"
         "[output]\nevery = 1000\nimage = false\nmesh_format = \"none\"\ncontrol_vtk = false\n";
}

struct Run {
  mbi::io::PointCache cache;
  nlohmann::json metrics;
};

Run run_text(const std::string& text, const mbi::test::TempDir& dir, const std::string& name) {
  const fs::path out = mbi::test::run_scene_text(text, dir, name);
  Run run{mbi::io::read_pc2(out / "dense.pc2"), {}};
  std::ifstream in(out / "metrics.json");
  run.metrics = nlohmann::json::parse(in);
  return run;
}

double diagonal(const Eigen::MatrixXd& P) { return (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm(); }

// The lowest dense vertex's height above the ground, over the model's diagonal, at frame k.
double gap(const Run& run, int k) {
  const Eigen::MatrixXd& P = run.cache.frames.at(static_cast<size_t>(k));
  return (P.col(1).minCoeff() - -0.8) / diagonal(run.cache.frames.front());
}

}  // namespace

TEST_CASE("contact = surface: the dense surface rests on the ground within 1e-3 of the diagonal, "
          "contact = control leaves the cage's margin", "[scenes][contact]") {
  mbi::test::TempDir dir("contact-rest");
  // the sanitizers make each frame slow: BI alone, damped harder, settled by frame 15
  const bool quick = mbi::test::kSanitized;
  const int frames = quick ? 25 : 75, settled = quick ? 15 : 45;  // the fall takes 8 frames
  const double damping = quick ? 8.0 : 2.0;
  const std::vector<std::string> methods = quick ? std::vector<std::string>{"bi"}
                                                 : std::vector<std::string>{"bi", "phong", "modified-bi"};
  for (const std::string& method : methods) {
    INFO(method);
    const Run surface = run_text(ball_scene("surface", method, frames, damping), dir, "surface-" + method);
    REQUIRE(surface.cache.frames.size() == static_cast<size_t>(frames + 1));
    CHECK(gap(surface, 0) > 0.04);  // it starts above the ground
    for (int k = settled; k <= frames; ++k) CHECK(std::abs(gap(surface, k)) <= 1e-3);
    // the approach side within the same bound at every frame, the impact included
    for (int k = 0; k <= frames; ++k) CHECK(gap(surface, k) >= -1e-3);
    const nlohmann::json& last = surface.metrics["frames"].back();
    CHECK(last["contact_points"].get<int>() >= 1);
    CHECK(last["newton_iterations"].get<int>() >= 1);
    CHECK(surface.metrics["contact"]["points"] == 482);
  }
  const Run control = run_text(ball_scene("control", methods.back(), frames, damping), dir, "control");
  for (int k = settled; k <= frames; ++k) CHECK(gap(control, k) > 0.01);  // the cage's margin
  CHECK_FALSE(control.metrics.contains("contact"));
  CHECK_FALSE(control.metrics["frames"].back().contains("contact_points"));
}

TEST_CASE("contact = control: the ground key keeps its meaning, the simulator's ground plane on the control nodes",
          "[scenes][contact]") {
  const Scene sc = parse_scene(ball_scene("control", "bi", 20), "ball.toml");
  const mbi::sim::Parameters& p = sc.simulation.parameters;
  CHECK(p.ground);
  CHECK(p.ground_plane.offset == -0.8);
  CHECK(p.newton_iterations == 1);
  CHECK(sc.colliders.empty());
  // the scene's driver steps exactly as a simulator built by hand with the same parameters
  const SceneModels m = load_models(sc);
  auto driver = make_driver(sc, m);
  mbi::sim::Simulator sim(m.U, m.T, sc.material, p);
  Eigen::MatrixXd X;
  for (int f = 0; f <= 20; ++f) {
    REQUIRE(driver->drive(f, X).ok);
    if (f > 0) REQUIRE(sim.step().success);
    REQUIRE(X == sim.positions());
  }
  CHECK(X.col(1).minCoeff() >= -0.8);  // the cage's nodes rest on the ground
}

TEST_CASE("contact = surface: the ground becomes a plane collider after the [[colliders]], Newton to a tolerance",
          "[scenes][contact]") {
  const std::string text = ball_scene("surface", "bi", 5) +
                           "[[colliders]]\nshape = \"sphere\"\ncenter = [0, 2, 0]\nradius = 0.5\nfriction = 0.3\n"
                           "motion = { velocity = [0, -1, 0], start = 0.5 }\n"
                           "[[colliders]]\nshape = \"box\"\ncenter = [3, 0, 0]\nhalf_extents = [0.5, 0.5, 0.5]\n"
                           "axes = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]\n"
                           "[[colliders]]\nshape = \"capsule\"\na = [0, 3, -1]\nb = [0, 3, 1]\nradius = 0.1\n";
  const Scene sc = parse_scene(text, "ball.toml");
  CHECK(sc.simulation.contact == ContactMode::Surface);
  CHECK_FALSE(sc.simulation.parameters.ground);  // no projection of the control nodes
  CHECK(sc.simulation.parameters.newton_iterations == kSurfaceNewtonIterations);
  REQUIRE(sc.colliders.size() == 4);
  CHECK(sc.colliders[0].shape == ColliderShape::Sphere);
  CHECK(sc.colliders[0].friction == 0.3);
  CHECK(sc.colliders[0].motion.velocity == Eigen::Vector3d(0, -1, 0));
  CHECK(sc.colliders[0].motion.start == 0.5);
  CHECK(sc.colliders[1].axes(1, 0) == 1.0);  // the first axis is the column [0, 1, 0]
  CHECK(sc.colliders[2].end == Eigen::Vector3d(0, 3, 1));
  CHECK(sc.colliders[3].shape == ColliderShape::Plane);
  CHECK(sc.colliders[3].point.y() == -0.8);
  CHECK(sc.colliders[3].normal == Eigen::Vector3d::UnitY());
  // the default tolerance follows the model: 1e-5 of its diagonal per substep
  const SceneModels m = load_models(sc);
  auto driver = make_driver(sc, m);
  const auto& sim = dynamic_cast<mbi::pipeline::SimulatorDriver&>(*driver).simulator();
  CHECK(sim.params().newton_tolerance ==
        Approx(surface_newton_tolerance(diagonal(m.dense.V), sc.simulation.parameters.dt)));
}

TEST_CASE("contact = surface: contact_select names the dense vertices that touch", "[scenes][contact]") {
  mbi::test::TempDir dir("contact-select");
  // the lower half of the ball's vertices (y <= 0)
  const std::string text = ball_scene("surface", "bi", 3) + "";
  std::string with = text;
  with.insert(with.find("[interpolation]"),
              "contact_stiffness = 1e8\ncontact_select = { half_space = { point = [0, 0, 0], normal = [0, -1, 0] } }\n");
  const Scene sc = parse_scene(with, "ball.toml");
  const SceneModels m = load_models(sc);
  const long below = (m.dense.V.col(1).array() <= 0).count();
  const Run run = run_text(with, dir, "select");
  CHECK(run.metrics["contact"]["points"] == below);
  CHECK(run.metrics["contact"]["stiffness"] == 1e8);
  CHECK(below < m.dense.V.rows());
}

TEST_CASE("contact = surface: contact_max_depth and contact_friction_velocity reach the contact", "[scenes][contact]") {
  std::string text = ball_scene("surface", "bi", 3);
  text.insert(text.find("[interpolation]"), "contact_max_depth = 0.02\ncontact_friction_velocity = 0.5\n");
  const Scene sc = parse_scene(text, "ball.toml");
  const SceneModels m = load_models(sc);
  mbi::pipeline::FramePipeline pipe = make_pipeline(sc, m, mbi::interp::embed(m.U, m.T, m.dense.V));
  const auto& contact = dynamic_cast<const mbi::pipeline::SimulatorDriver&>(pipe.driver()).contact();
  REQUIRE(contact);
  CHECK(contact->max_depth() == 0.02);
  CHECK(contact->friction_velocity() == 0.5);
  const Scene plain = parse_scene(ball_scene("surface", "bi", 3), "ball.toml");
  mbi::pipeline::FramePipeline defaults = make_pipeline(plain, m, mbi::interp::embed(m.U, m.T, m.dense.V));
  CHECK(dynamic_cast<const mbi::pipeline::SimulatorDriver&>(defaults.driver()).contact()->max_depth() != 0.02);
}

TEST_CASE("contact = surface: a collider overlapping the model at rest is an error naming it", "[scenes][contact]") {
  std::string text = ball_scene("surface", "bi", 5) + "[[colliders]]\nshape = \"sphere\"\ncenter = [0, 3, 0]\nradius = 0.1\n";
  text.replace(text.find("ground = -0.8"), 13, "ground = -0.3");  // the ball's bottom is at y = -0.5
  const Scene sc = parse_scene(text, "ball.toml");
  const SceneModels m = load_models(sc);
  try {
    make_driver(sc, m);
    FAIL("no error");
  } catch (const Error& e) {
    CHECK_THAT(e.what(), Catch::Matchers::Contains("ball.toml: simulation.contact: collider 1 overlaps the model at rest") &&
                             Catch::Matchers::Contains("then the ground"));
  }
}

TEST_CASE("contact keys and [[colliders]]: bad input is an error naming the key and the collider", "[scenes][contact]") {
  const std::string base = ball_scene("surface", "bi", 5);
  auto error = [&](const std::string& text) {
    try {
      parse_scene(text, "s.toml");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  auto contains = [](const std::string& what) { return Catch::Matchers::Contains(what); };
  const std::string sphere = "[[colliders]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n";
  CHECK_THAT(error(base + sphere + "[[colliders]]\nshape = \"cone\"\n"),
             contains("colliders[1].shape: unknown value \"cone\"") && contains("plane, sphere, box, capsule"));
  CHECK_THAT(error(base + "[[colliders]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\n"),
             contains("s.toml:") && contains("colliders[0].radius: missing"));
  CHECK_THAT(error(base + sphere + "[[colliders]]\nshape = \"mesh\"\n"), contains("s.toml:") && contains("colliders[1].path: missing"));
  CHECK_THAT(error(base + "[[colliders]]\nshape = \"capsule\"\na = [0, 0, 0]\nradius = 1\n"),
             contains("colliders[0].b: missing"));
  CHECK_THAT(error(base + sphere + "friction = nan\n"), contains("colliders[0].friction: must be finite"));
  CHECK_THAT(error(base + sphere + "friction = -0.5\n"), contains("colliders[0].friction: value -0.5 out of range"));
  CHECK_THAT(error(base + "[[colliders]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1\n"),
             contains("colliders[0].radius: value -1 out of range"));
  CHECK_THAT(error(base + "[[colliders]]\nshape = \"plane\"\nradius = 1\n"), contains("colliders[0].radius: unknown key"));
  CHECK_THAT(error(base + "[[colliders]]\nshape = \"plane\"\nnormal = [0, 0, 0]\n"),
             contains("colliders[0]: normal"));
  CHECK_THAT(error(base + "[[colliders]]\nshape = \"box\"\ncenter = [0, 0, 0]\nhalf_extents = [1, 1, 1]\n"
                          "axes = [[1, 0, 0], [1, 0, 0], [0, 0, 1]]\n"),
             contains("colliders[0]: axes"));
  CHECK_THAT(error(base + sphere + "motion = { stop = -1 }\n"), contains("colliders[0].motion.stop"));
  CHECK_THAT(error(base + "[[colliders]]\nradius = 1\n"), contains("colliders[0].shape: missing"));
  // the contact keys
  std::string foo = base;
  foo.replace(foo.find("\"surface\""), 9, "\"foo\"");
  CHECK_THAT(error(foo), contains("simulation.contact: unknown value \"foo\" (expected one of: control, surface)"));
  const std::string control = ball_scene("control", "bi", 5);
  CHECK_THAT(error(control + sphere), contains("colliders: [[colliders]] need simulation.contact = \"surface\""));
  std::string stiff = control;
  stiff.insert(stiff.find("[interpolation]"), "contact_stiffness = 1e5\n");
  CHECK_THAT(error(stiff), contains("simulation.contact_stiffness: needs contact = \"surface\""));
  std::string zero = base;
  zero.insert(zero.find("[interpolation]"), "contact_stiffness = 0\n");
  CHECK_THAT(error(zero), contains("simulation.contact_stiffness: value 0 out of range"));
  std::string damped = base;
  damped.insert(damped.find("[interpolation]"), "damping_stiffness = 0.01\n");
  CHECK_THAT(error(damped), contains("simulation.damping_stiffness: must be 0 with contact = \"surface\""));
  std::string nothing = base;
  nothing.erase(nothing.find("ground = -0.8\n"), 14);
  CHECK_THAT(error(nothing), contains("simulation.contact: \"surface\" needs [[colliders]] or simulation.ground"));
  for (const char* key : {"contact_max_depth", "contact_friction_velocity"}) {
    std::string bad = base, unused = control;
    bad.insert(bad.find("[interpolation]"), std::string(key) + " = -1\n");
    CHECK_THAT(error(bad), contains(std::string("simulation.") + key + ": value -1 out of range"));
    unused.insert(unused.find("[interpolation]"), std::string(key) + " = 1\n");
    CHECK_THAT(error(unused), contains(std::string("simulation.") + key + ": needs contact = \"surface\""));
  }
  std::string tolerance = base;
  tolerance.insert(tolerance.find("[interpolation]"), "newton_tolerance = -1\n");
  CHECK_THAT(error(tolerance), contains("simulation.newton_tolerance: value -1 out of range"));
}
