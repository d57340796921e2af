// The viewer: picking and camera maths headless; then `mbi view` end to end under Xvfb with
// scripted input (pokes, violent pokes, direct-mode drags, replay of a recording), checked
// through its per-frame report and screenshots.
#include <catch2/catch.hpp>

#include <mbi/io/image.hpp>
#include <mbi/viewer/camera.hpp>
#include <mbi/viewer/layout.hpp>

#include "common/grid_meshes.hpp"
#include "viewer_run.hpp"

#include <cmath>
#include <map>
#include <sstream>

namespace fs = std::filesystem;
using mbi::test::source_dir;
using mbi::test::TempDir;
using namespace mbi::viewer;

namespace {

using Run = mbi::test::ViewRun;
using mbi::test::non_background;
using mbi::test::view;

nlohmann::json report(const fs::path& file) { return mbi::test::read_report(file); }

Eigen::Vector3d vec(const nlohmann::json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

// Fraction of pixels that differ by more than `tol` in any channel.
double differing(const mbi::io::Image& a, const mbi::io::Image& b, int tol = 8) {
  REQUIRE(a.width == b.width);
  REQUIRE(a.height == b.height);
  long long n = 0;
  for (size_t i = 0; i < a.rgb.size(); i += 3) {
    bool diff = false;
    for (int c = 0; c < 3; ++c) diff = diff || std::abs(int(a.rgb[i + c]) - int(b.rgb[i + c])) > tol;
    n += diff;
  }
  return double(n) / (a.width * a.height);
}

std::string q(const fs::path& p) { return mbi::test::quoted(p); }

}  // namespace

TEST_CASE("viewer picking: the ray under a pixel hits the expected point, also at framebuffer scale 2", "[viewer]") {
  const mbi::test::Mesh m = mbi::test::box_tet_mesh(2, 2, 2, Eigen::Vector3d(2, 1, 1));
  // the box's boundary triangles: faces of the six sides from the tets' boundary faces
  Eigen::MatrixXd V = m.U;
  std::vector<Eigen::Vector3i> tris;
  for (Eigen::Index e = 0; e < m.T.rows(); ++e)
    for (int skip = 0; skip < 4; ++skip) {
      Eigen::Vector3i f;
      for (int k = 0, w = 0; k < 4; ++k)
        if (k != skip) f(w++) = m.T(e, k);
      tris.push_back(f);
    }
  Eigen::MatrixXi F(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t i = 0; i < tris.size(); ++i) F.row(static_cast<Eigen::Index>(i)) = tris[i].transpose();
  Camera cam;
  cam.frame(Eigen::Vector3d::Zero(), Eigen::Vector3d(2, 1, 1));
  const int w = 800, h = 600;
  // a point on the box's visible surface: the top face (y = 1) seen from above
  cam.pitch = 0.9;
  const Eigen::Vector3d expected(1.3, 1.0, 0.4);
  const Eigen::Vector2d px = cam.project(expected, w, h);
  for (double scale : {1.0, 2.0}) {
    // the framebuffer pixel a HiDPI screen reports, converted back to window coordinates
    const Eigen::Vector2d fb = px * scale;
    const Eigen::Vector2d win = window_from_framebuffer(fb, scale);
    const std::optional<Hit> hit = cast(cam.ray(win.x(), win.y(), w, h), V, F);
    REQUIRE(hit);
    CHECK((hit->point - expected).norm() < 1e-9);
    CHECK(std::abs(hit->bary.sum() - 1) < 1e-12);
  }
  // a ray past the model hits nothing
  CHECK_FALSE(cast(cam.ray(2, 2, w, h), V, F));
}

TEST_CASE("viewer pokes: the spring's response does not depend on mass or size, and the target is bounded", "[viewer]") {
  // natural frequency sqrt(k / m) is the same for any mass
  for (double mass : {1e-3, 1.0, 1e4}) CHECK(std::sqrt(poke_stiffness(mass, 0.2) / mass) == Approx(2 * std::acos(-1.0) / 0.2));
  Ray r;
  r.origin = Eigen::Vector3d(100, 0, -10);
  r.direction = Eigen::Vector3d(0, 0, 1);
  const Eigen::Vector3d grab(0, 0, 0);
  const Eigen::Vector3d t = poke_target(r, grab, Eigen::Vector3d(0, 0, 1), 2.0);
  CHECK((t - grab).norm() == Approx(2.0));  // 100 away asked, 2 given
  CHECK(t.allFinite());
  r.direction = Eigen::Vector3d(1, 0, 0);  // parallel to the plane: stays at the grab
  CHECK(poke_target(r, grab, Eigen::Vector3d(0, 0, 1), 2.0).allFinite());
}

TEST_CASE("mbi view without a display: one line, exit code 2", "[viewer]") {
  TempDir dir("view");
  const Run r = view(q(fs::path(source_dir()) / "scenes" / "twist-bar.toml") + " --frames 2", dir, false);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::StartsWith("mbi view: error: no display"));
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

TEST_CASE("mbi view: a scripted poke pulls the grabbed material point toward the cursor", "[viewer][xvfb]") {
  TempDir dir("view");
  const std::string scene = q(fs::path(source_dir()) / "scenes" / "twist-bar.toml");
  std::ofstream(dir / "poke.txt") << [] {
    std::ostringstream s;
    s << "5 press 960 420 0\n";
    for (int f = 6; f < 40; ++f) s << f << " move " << 960 + 4 * (f - 5) << " " << 420 - 3 * (f - 5) << "\n";
    s << "40 release 1096 318 0\n";
    return s.str();
  }();
  const Run a = view(scene + " --frames 45 --no-panel --script " + q(dir / "poke.txt") + " --screenshot " +
                         q(dir / "poked.png") + " --report " + q(dir / "poked.json"),
                     dir);
  INFO(a.err);
  REQUIRE(a.code == 0);
  const Run b = view(scene + " --frames 45 --no-panel --screenshot " + q(dir / "plain.png"), dir);
  REQUIRE(b.code == 0);
  const nlohmann::json rep = report(dir / "poked.json");
  int poked = 0;
  double first_gap = -1, last_gap = -1, travelled = 0;
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  for (const auto& fr : rep) {
    CHECK(fr["finite"].get<bool>());
    if (!fr.contains("poke")) continue;
    const Eigen::Vector3d p = vec(fr["poke"]["point"]), t = vec(fr["poke"]["target"]);
    if (poked++ == 0) start = p, first_gap = (t - p).norm();
    last_gap = (t - p).norm();
    travelled = (p - start).norm();
  }
  CHECK(poked >= 30);
  INFO("gap first " << first_gap << ", last " << last_gap << ", travelled " << travelled);
  CHECK(travelled > 0.3);          // the material point followed the cursor (bar 1 x 1 x 6 m)
  CHECK(last_gap < 0.5);           // and stays near the target
  const mbi::io::Image poked_img = mbi::io::read_png(dir / "poked.png"), plain = mbi::io::read_png(dir / "plain.png");
  CHECK(non_background(poked_img) > 0.05);
  CHECK(differing(poked_img, plain) > 0.005);
}

TEST_CASE("mbi view: a violent poke (far off screen, flicked every frame) stays bounded and recovers", "[viewer][xvfb][long]") {
  TempDir dir("view");
  const std::string scene = q(fs::path(source_dir()) / "scenes" / "cantilever.toml");
  std::ofstream(dir / "flick.txt") << [] {
    std::ostringstream s;
    s << "3 press 960 330 0\n";
    for (int f = 4; f < 40; ++f) s << f << " move " << (f % 2 ? 60000 : -60000) << " " << (f % 2 ? -50000 : 50000) << "\n";
    s << "40 release 0 0 0\n";
    return s.str();
  }();
  const Run r = view(scene + " --frames 120 --no-panel --script " + q(dir / "flick.txt") + " --report " + q(dir / "flick.json"),
                     dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json rep = report(dir / "flick.json");
  REQUIRE(rep.size() == 120);
  int poked = 0;
  double peak = 0, max_disp = 0;
  for (const auto& fr : rep) {
    REQUIRE(fr["finite"].get<bool>());
    poked += fr.contains("poke");
    const double e = fr["kinetic_energy"].get<double>() + fr["elastic_energy"].get<double>();
    REQUIRE(std::isfinite(e));
    peak = std::max(peak, e);
    max_disp = std::max(max_disp, fr["max_displacement"].get<double>());
  }
  CHECK(poked >= 30);
  const double model = 4.0;  // the cantilever: a 4 m cylinder
  INFO("peak energy " << peak << " J, largest displacement " << max_disp << " m");
  CHECK(max_disp < 1.5 * model);  // the bounded spring cannot fling it away
  // after the release the motion decays (damped): the last frames move far less than the peak
  const double end_kinetic = rep.back()["kinetic_energy"].get<double>();
  double kinetic_peak = 0;
  for (const auto& fr : rep) kinetic_peak = std::max(kinetic_peak, fr["kinetic_energy"].get<double>());
  CHECK(end_kinetic < 0.2 * kinetic_peak);
}

TEST_CASE("mbi view: a drag in direct mode brings the handle to its target and moves the free vertices", "[viewer][xvfb]") {
  TempDir dir("view");
  const std::string scene = q(fs::path(source_dir()) / "scenes" / "twist-bar.toml");
  // where the control vertices are on screen
  const Run probe = view(scene + " --frames 1 --paused --no-panel --report " + q(dir / "probe.json"), dir);
  REQUIRE(probe.code == 0);
  const nlohmann::json cs = report(dir / "probe.json")[0]["control_window"];
  // the control vertex farthest right in the right panel: a free (not kinematic) corner
  size_t v = 0;
  for (size_t i = 0; i < cs.size(); ++i)
    if (cs[i][0].get<double>() > cs[v][0].get<double>()) v = i;
  const double x = cs[v][0], y = cs[v][1];
  std::ofstream(dir / "drag.txt") << "1 key d\n2 press " << x << " " << y << " 0\n"
                                  << "3 move " << x + 30 << " " << y + 20 << "\n4 move " << x + 60 << " " << y + 40
                                  << "\n5 move " << x + 80 << " " << y + 50 << "\n6 release " << x + 80 << " " << y + 50
                                  << " 0\n";
  const Run r = view(scene + " --frames 10 --paused --no-panel --script " + q(dir / "drag.txt") + " --report " +
                         q(dir / "drag.json") + " --record " + q(dir / "recorded.txt") + " --screenshot " + q(dir / "a.png"),
                     dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json rep = report(dir / "drag.json");
  const auto& last = rep.back();
  REQUIRE(last["direct"].get<bool>());
  REQUIRE(last["handles"].size() == 1);
  const Eigen::Vector3d pos = vec(last["handles"][0]["position"]), tgt = vec(last["handles"][0]["target"]);
  CHECK((pos - tgt).norm() < 1e-6);                         // the handle is where it was dragged
  CHECK(last["max_displacement"].get<double>() > 0.1);       // the drag moved it
  // a recording replays to the same picture (the same handle, the same targets)
  const Run b = view(scene + " --frames 10 --paused --no-panel --script " + q(dir / "recorded.txt") + " --screenshot " +
                         q(dir / "b.png"),
                     dir);
  REQUIRE(b.code == 0);
  CHECK(differing(mbi::io::read_png(dir / "a.png"), mbi::io::read_png(dir / "b.png")) < 0.001);
}

TEST_CASE("mbi view: the 2D image-warp scene draws the warped picture", "[viewer][xvfb]") {
  TempDir dir("view");
  const Run r = view(q(fs::path(source_dir()) / "scenes" / "image-warp.toml") + " --frames 25 --no-panel --screenshot " +
                         q(dir / "warp.png"),
                     dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const mbi::io::Image img = mbi::io::read_png(dir / "warp.png");
  CHECK(non_background(img) > 0.2);
}

TEST_CASE("mbi view --gpu: auto picks the CPU kernel on llvmpipe, and both evaluators draw the same picture",
          "[viewer][xvfb]") {
  TempDir dir("view");
  const std::string scene = q(fs::path(source_dir()) / "scenes" / "twist-bar.toml");
  std::map<std::string, mbi::io::Image> shots;
  for (const std::string gpu : {"auto", "on", "off"}) {
    const fs::path rep = dir / (gpu + ".json"), shot = dir / (gpu + ".png");
    const Run r = view(scene + " --frames 3 --paused --no-panel --gpu " + gpu + " --report " + q(rep) +
                           " --screenshot " + q(shot),
                       dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
    const nlohmann::json ev = report(rep).back()["evaluator"];
    const std::string name = ev["name"];
    INFO(gpu << ": " << name << " (" << ev["why"].get<std::string>() << ")");
    CHECK(name.rfind(gpu == "on" ? "gpu" : "cpu", 0) == 0);  // Xvfb's OpenGL is llvmpipe
    if (gpu == "auto") CHECK(ev["why"].get<std::string>().find("llvmpipe") != std::string::npos);
    shots[gpu] = mbi::io::read_png(shot);
  }
  CHECK(non_background(shots["off"]) > 0.01);
  CHECK(differing(shots["on"], shots["off"]) < 0.002);
}

TEST_CASE("viewer layout: the panel and the views never overlap, at framebuffer scale 1 and 2, open or folded",
          "[viewer]") {
  for (const double scale : {1.0, 2.0})
    for (const int views : {1, 2})
      for (const bool collapsed : {false, true})
        for (const auto& [w, h] : {std::pair{1280, 720}, std::pair{640, 480}, std::pair{160, 120}, std::pair{3000, 900}}) {
          const int fbw = static_cast<int>(w * scale), fbh = static_cast<int>(h * scale);
          const Layout l = make_layout(w, h, fbw, fbh, views, true, collapsed);
          INFO(w << " x " << h << " at scale " << scale << ", " << views << " views, folded " << collapsed);
          REQUIRE(l.views.size() == static_cast<size_t>(views));
          CHECK(l.panel.w > 0);
          double covered = l.panel.w;
          for (size_t k = 0; k < l.views.size(); ++k) {
            const Rect& v = l.views[k];
            const Rect& fb = l.view_viewports[k];
            CHECK_FALSE(overlap(l.panel, v));
            for (size_t j = 0; j < k; ++j) CHECK_FALSE(overlap(l.views[j], v));
            CHECK(fb.x >= l.panel.w * scale - 1e-9);  // in framebuffer pixels too
            CHECK(fb.x + fb.w <= fbw);
            CHECK(fb.x == Approx(v.x * scale));
            CHECK(v.w > 0);
            covered += v.w;
          }
          CHECK(covered == Approx(w).margin(1.0));  // the views fill the rest of the window
        }
  const Layout none = make_layout(800, 600, 800, 600, 2, false, false);
  CHECK(none.panel.w == 0);
  CHECK(none.views[0].x == 0);
}

TEST_CASE("mbi view: the docked panel covers no view, each view is labelled with its method", "[viewer][xvfb]") {
  TempDir dir("view");
  const Run r = view(q(fs::path(source_dir()) / "scenes" / "twist-bar.toml") + " --frames 3 --method modified-bi --report " +
                         q(dir / "layout.json"),
                     dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json l = report(dir / "layout.json").back()["layout"];
  auto rect = [](const nlohmann::json& j) { return Rect{j[0], j[1], j[2], j[3]}; };
  const Rect panel = rect(l["panel"]);
  CHECK(panel.w > 100);
  REQUIRE(l["views"].size() == 2);
  CHECK(l["views"][0]["label"] == "bi");
  CHECK(l["views"][1]["label"] == "modified-bi");
  for (const auto& v : l["views"]) CHECK_FALSE(overlap(panel, rect(v["rect"])));
  CHECK_FALSE(overlap(rect(l["views"][0]["rect"]), rect(l["views"][1]["rect"])));
}
