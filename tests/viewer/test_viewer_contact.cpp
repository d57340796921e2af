// Contact in the viewer: a ball resting on a ground plane with a sphere collider beside it; a
// scripted mouse drag carries the sphere into the ball. The sphere follows the cursor on the
// plane facing the camera, the ball is pushed away, points touch while it pushes, and no dense
// point goes deeper into a collider than the contact's max depth (the depth guarded points never
// pass); the t key switches contact off. Checked through the per-frame report under Xvfb.
#include <catch2/catch.hpp>

#include <mbi/viewer/camera.hpp>

#include "scenes/contact_ball.hpp"
#include "viewer_run.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using mbi::test::TempDir;

namespace {

Eigen::Vector3d vec(const nlohmann::json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

// The ball on the ground y = -0.5 (frictionless), a sphere of radius 0.3 beside it (0.2 m away).
fs::path write_scene(const TempDir& dir) {
  fs::copy_file(mbi::test::ball_file(), dir / "ball.obj");  // the contact tests' ball
  const fs::path scene = dir / "push.toml";
  std::ofstream(scene) << "name = \"push\"\n[dense]\npath = \"ball.obj\"\n[control]\ngenerate_vertices = 60\n"
                          "[material]\nyoung = 2e4\npoisson = 0.3\ndensity = 100\n"
                          "[simulation]\ndt = 0.0333333\ngravity = [0, -9.81, 0]\ndamping_mass = 2.0\n"
                          "ground = -0.5\ncontact = \"surface\"\n"
                          "[[colliders]]\nshape = \"sphere\"\ncenter = [1.0, 0.0, 0.0]\nradius = 0.3\n"
                          "[interpolation]\nmethod = \"bi\"\n";
  return scene;
}

// The report's camera and the window position of world point p in the last view.
Eigen::Vector2d window_of(const nlohmann::json& frame, const Eigen::Vector3d& p) {
  mbi::viewer::Camera cam;
  cam.target = vec(frame["camera"]["target"]);
  cam.radius = frame["camera"]["radius"].get<double>();
  cam.yaw = frame["camera"]["yaw"].get<double>();
  cam.pitch = frame["camera"]["pitch"].get<double>();
  const nlohmann::json& r = frame["layout"]["views"].back()["rect"];
  const int height = frame["layout"]["window"][1].get<int>();
  const Eigen::Vector2d q = cam.project(p, static_cast<int>(std::lround(r[2].get<double>())), height);
  return {q.x() + r[0].get<double>(), q.y()};
}

}  // namespace

TEST_CASE("mbi view: a sphere collider dragged with the mouse pushes the model, touching it without penetrating",
          "[viewer][xvfb][contact]") {
  TempDir dir("view-contact");
  const fs::path scene = write_scene(dir);
  const std::string common = mbi::test::quoted(scene) + " --width 900 --height 600 --no-split --report ";
  // where the sphere is on screen (the camera frames the control mesh)
  const mbi::test::ViewRun probe = view(common + mbi::test::quoted(dir / "probe.json") + " --frames 1", dir);
  INFO(probe.err);
  REQUIRE(probe.code == 0);
  const nlohmann::json first = mbi::test::read_report(dir / "probe.json").at(0);
  REQUIRE(first.contains("contact"));
  // the [[colliders]], then the ground
  REQUIRE(first["contact"]["colliders"].size() == 2);
  CHECK(first["contact"]["colliders"][0]["shape"] == "sphere");
  CHECK(first["contact"]["colliders"][1]["shape"] == "plane");
  const Eigen::Vector3d center0 = vec(first["contact"]["colliders"][0]["point"]);
  // drag the sphere 0.7 m toward the ball (-x), over 20 frames (2.1 m/s), then let go
  const Eigen::Vector3d push(-0.7, 0, 0);
  const Eigen::Vector2d from = window_of(first, center0), to = window_of(first, center0 + push);
  const int press = 10, last_move = 30, release = 40, off = 45, frames = 50;
  std::ostringstream script;
  script.precision(10);
  script << press << " press " << from.x() << " " << from.y() << " 0\n";
  for (int f = press + 1; f <= last_move; ++f) {
    const Eigen::Vector2d p = from + (to - from) * double(f - press) / (last_move - press);
    script << f << " move " << p.x() << " " << p.y() << "\n";
  }
  script << release << " release " << to.x() << " " << to.y() << " 0\n";
  script << off << " key t\n";  // contact off
  std::ofstream(dir / "drag.txt") << script.str();
  const mbi::test::ViewRun run = view(common + mbi::test::quoted(dir / "drag.json") + " --frames " + std::to_string(frames) +
                                          " --script " + mbi::test::quoted(dir / "drag.txt"),
                                      dir);
  INFO(run.err);
  REQUIRE(run.code == 0);
  const nlohmann::json rep = mbi::test::read_report(dir / "drag.json");
  REQUIRE(rep.size() == static_cast<size_t>(frames));
  // the cursor's move on the plane facing the camera: the push less its part along the view
  mbi::viewer::Camera cam;
  cam.yaw = first["camera"]["yaw"].get<double>(), cam.pitch = first["camera"]["pitch"].get<double>();
  const Eigen::Vector3d along = push - push.dot(cam.direction()) * cam.direction();
  const double pixel = 2 * first["camera"]["radius"].get<double>() / first["layout"]["window"][1].get<double>();
  const double max_depth = first["contact"]["max_depth"].get<double>();
  const Eigen::Vector3d mean_before = vec(rep.at(press)["contact"]["points_mean"]);
  int touching_frames = 0, grabbed_frames = 0;
  for (int frame = 0; frame < frames; ++frame) {  // the script's frames (the report's rows)
    const nlohmann::json& fr = rep.at(static_cast<size_t>(frame));
    const nlohmann::json& c = fr["contact"];
    CHECK(fr["finite"].get<bool>());
    CHECK(c["on"].get<bool>() == (frame < off));
    if (frame >= off) CHECK(c["touching"].get<int>() == 0);  // no contact solved: none counted
    grabbed_frames += c["colliders"][0]["grabbed"].get<bool>();
    if (frame > press + 5 && frame <= release) touching_frames += c["colliders"][0]["gap"].get<double>() <= 0;
    INFO("frame " << frame << ": deepest " << c["deepest"].get<double>() << " m, max depth " << max_depth << " m");
    if (frame < off) CHECK(c["deepest"].get<double>() >= -max_depth);  // no dense point deeper in the ground or the sphere
  }
  CHECK(grabbed_frames == release - press);
  CHECK(touching_frames >= 5);  // the sphere touched the ball while pushing it
  int pushing = 0;  // the driver's count (the panel's "touching") while the sphere pushes
  for (int f = press + 10; f <= last_move; ++f) pushing += rep.at(f)["contact"]["touching"].get<int>() > 0;
  CHECK(pushing >= 5);
  const Eigen::Vector3d center1 = vec(rep.back()["contact"]["colliders"][0]["point"]);
  INFO("sphere moved " << (center1 - center0).transpose() << ", the cursor asked " << along.transpose());
  CHECK((center1 - center0 - along).norm() < 2 * pixel);  // followed the cursor to a pixel or two
  const Eigen::Vector3d mean_after = vec(rep.at(off - 1)["contact"]["points_mean"]);
  INFO("the ball's points' mean moved " << (mean_after - mean_before).transpose());
  CHECK(mean_after.x() - mean_before.x() < -0.1);  // pushed along the drag, away from the sphere
  // where the sphere was left it would hold the ball as it was before the push over 0.1 m deep,
  // yet no point is inside it: the points near it moved out of its way
  INFO("the sphere's centre ends " << (center1 - mean_before).norm() << " m from the ball's before the push");
  CHECK((center1 - mean_before).norm() < 0.5 + 0.3 - 0.1);
  CHECK(rep.at(off - 1)["contact"]["colliders"][0]["gap"].get<double>() >= -max_depth);
}
