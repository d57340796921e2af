// The creases in colour in `mbi view` under Xvfb: BI's surface near the control faces is hotter
// than modified-BI's, in the direction of the discontinuity table (from `mbi run` at the same
// frame), from the viewer's own per-vertex values and from the pixels; the legend is drawn; at
// rest nothing glows (negative control); toggled off (g key), the picture is the plain one.
#include <catch2/catch.hpp>

#include <mbi/io/io.hpp>
#include <mbi/pipeline/creases.hpp>
#include <mbi/scenes/runner.hpp>

#include "viewer_run.hpp"

#include <cmath>
#include <fstream>

namespace fs = std::filesystem;
using mbi::test::source_dir;
using mbi::test::TempDir;

namespace {

std::string q(const fs::path& p) { return mbi::test::quoted(p); }

std::string twist_bar() { return q(fs::path(source_dir()) / "scenes" / "twist-bar.toml"); }

// Mean red minus blue (0..255) over the non-white pixels of a view's rectangle (logical = framebuffer
// pixels here), above the legend: crease_color's "hotness".
double hotness(const mbi::io::Image& img, const nlohmann::json& rect, double bottom) {
  double sum = 0;
  long n = 0;
  for (int y = static_cast<int>(rect[1].get<double>()) + 30; y < static_cast<int>(bottom); ++y)
    for (int x = static_cast<int>(rect[0].get<double>()); x < static_cast<int>(rect[0].get<double>() + rect[2].get<double>()); ++x) {
      const std::uint8_t* p = img.at(x, y);
      if (p[0] == 255 && p[1] == 255 && p[2] == 255) continue;
      sum += p[0] - p[2];
      ++n;
    }
  REQUIRE(n > 1000);
  return sum / n;
}

struct Shown {
  nlohmann::json frame;
  mbi::io::Image shot;
};

Shown view_creases(const TempDir& dir, const std::string& name, const std::string& args) {
  const fs::path rep = dir / (name + ".json"), shot = dir / (name + ".png");
  // plain looks: the pixels measured are the model's on white (no ground, no shadow)
  const mbi::test::ViewRun r = mbi::test::view(
      twist_bar() + " --looks plain --no-panel --report " + q(rep) + " --screenshot " + q(shot) + " " + args, dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  return {mbi::test::read_report(rep).back(), mbi::io::read_png(shot)};
}

}  // namespace

TEST_CASE("mbi view --creases: BI glows at the control faces where the table says it jumps more, modified-BI does not",
          "[viewer][xvfb][creases][long]") {
  TempDir dir("view");
  const Shown s = view_creases(dir, "lit", "--creases --frames 40");
  const nlohmann::json& c = s.frame["creases"];
  REQUIRE(c["views"].size() == 2);
  REQUIRE(c["views"][0]["label"] == "bi");
  REQUIRE(c["views"][1]["label"] == "modified-bi");
  // the discontinuity table of the same scene at the same frame
  mbi::scenes::RunOptions o;
  o.out_dir = dir / "run";
  o.frames = s.frame["frame"].get<int>();
  o.gpu = mbi::scenes::GpuUse::Off;
  const mbi::scenes::RunResult run = mbi::scenes::run_scene(mbi::scenes::load_scene(source_dir() / "scenes" / "twist-bar.toml"), o);
  REQUIRE_FALSE(run.failed);
  REQUIRE(run.last_table.bi.mean > run.last_table.modified_bi.mean);
  // the viewer's face jumps in the same order, and its per-vertex scale near the faces (0..1)
  CHECK(c["views"][0]["mean_jump"].get<double>() > c["views"][1]["mean_jump"].get<double>());
  const double near_bi = c["views"][0]["mean_near"], near_mbi = c["views"][1]["mean_near"];
  INFO("near the faces: BI " << near_bi << ", modified-BI " << near_mbi);
  CHECK(near_bi > near_mbi + 0.15);
  // the pixels: BI's view hotter by 25 of 255 or more (the legend's rows left out)
  const nlohmann::json& views = s.frame["layout"]["views"];
  const double legend_top = c["legend"][1].get<double>() - 30;
  const double bi = hotness(s.shot, views[0]["rect"], legend_top), mbi = hotness(s.shot, views[1]["rect"], legend_top);
  INFO("pixels: BI " << bi << ", modified-BI " << mbi);
  CHECK(bi > mbi + 25);
  // the legend: its bar's ends are the scale's ends (within 12 of 255), its top the largest jump
  const double lx = c["legend"][0], ly = c["legend"][1], lw = c["legend"][2], lh = c["legend"][3];
  REQUIRE(lw > 100);
  const std::uint8_t* cold = s.shot.at(static_cast<int>(lx + 3), static_cast<int>(ly + lh / 2));
  const std::uint8_t* hot = s.shot.at(static_cast<int>(lx + lw - 4), static_cast<int>(ly + lh / 2));
  const Eigen::Vector3d c0 = mbi::pipeline::crease_color(0) * 255, c1 = mbi::pipeline::crease_color(1) * 255;
  for (int k = 0; k < 3; ++k) {
    CHECK(std::abs(cold[k] - c0(k)) < 12);
    CHECK(std::abs(hot[k] - c1(k)) < 12);
  }
  CHECK(c["top"].get<double>() > 0);
}

TEST_CASE("mbi view --creases: at rest nothing glows, the g key turns the colours off and gives the plain picture",
          "[viewer][xvfb][creases]") {
  TempDir dir("view");
  // negative control: paused at the rest pose, no jump anywhere: both views equally cold
  const Shown rest = view_creases(dir, "rest", "--creases --paused --frames 3");
  const nlohmann::json& c = rest.frame["creases"];
  CHECK(c["views"][0]["mean_near"].get<double>() == Approx(c["views"][1]["mean_near"].get<double>()).margin(1e-6));
  const nlohmann::json& views = rest.frame["layout"]["views"];
  const double bottom = c["legend"][1].get<double>() - 30;
  CHECK(std::abs(hotness(rest.shot, views[0]["rect"], bottom) - hotness(rest.shot, views[1]["rect"], bottom)) < 3);
  // toggled off by the g key: the same picture as a session that never had them, no report entry
  std::ofstream(dir / "g.txt") << "1 key g\n";
  const Shown off = view_creases(dir, "off", "--creases --paused --frames 3 --script " + q(dir / "g.txt"));
  const Shown plain = view_creases(dir, "plain", "--paused --frames 3");
  CHECK_FALSE(off.frame.contains("creases"));
  CHECK(off.shot.rgb == plain.shot.rgb);
}
