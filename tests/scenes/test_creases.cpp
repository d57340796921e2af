// `mbi run`'s pictures with output.creases (the colours: tests/pipeline/test_creases.cpp): BI's
// panel is hotter than modified-BI's where the table says BI jumps more; at rest nothing glows
// (negative control); with the option off the pictures are the usual ones.
#include <catch2/catch.hpp>

#include <mbi/io/io.hpp>
#include <mbi/pipeline/creases.hpp>
#include <mbi/scenes/runner.hpp>

#include "common/files.hpp"
#include "common/temp_dir.hpp"

#include <cmath>

namespace fs = std::filesystem;
using namespace mbi::scenes;
using mbi::test::source_dir;

namespace {

// Mean of red minus blue (0..255) over the non-white pixels of columns [x0, x1), rows [0, y1):
// crease_color's "hotness", which Lambert shading scales alike in both panels.
double hotness(const mbi::io::Image& img, int x0, int x1, int y1) {
  double sum = 0;
  long n = 0;
  for (int y = 0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const std::uint8_t* p = img.at(x, y);
      if (p[0] == 255 && p[1] == 255 && p[2] == 255) continue;
      sum += p[0] - p[2];
      ++n;
    }
  REQUIRE(n > 100);
  return sum / n;
}

RunResult run_twist(const fs::path& out, int frames, bool creases) {
  Scene sc = load_scene(source_dir() / "scenes" / "twist-bar.toml");
  sc.output.creases = creases;
  sc.output.mesh_format = MeshFormat::None;
  RunOptions o;
  o.out_dir = out;
  o.frames = frames;
  o.gpu = GpuUse::Off;
  const RunResult r = run_scene(sc, o);
  REQUIRE_FALSE(r.failed);
  return r;
}

}  // namespace

TEST_CASE("mbi run with output.creases: BI's panel glows where the table says it jumps more, off: the usual pictures",
          "[creases][runner][long]") {
  mbi::test::TempDir dir("creases");
  const RunResult on = run_twist(dir / "on", 30, true);
  const RunResult off = run_twist(dir / "off", 30, false);
  // the table: BI's gradient jumps far larger than modified-BI's
  REQUIRE(on.last_table.bi.mean > 10 * on.last_table.modified_bi.mean);
  const mbi::io::Image lit = mbi::io::read_png(mbi::io::frame_path(dir / "on" / "frame", 30, ".png"));
  const mbi::io::Image plain = mbi::io::read_png(mbi::io::frame_path(dir / "off" / "frame", 30, ".png"));
  // the panels side by side (8-pixel gap), the legend strip under them
  REQUIRE(lit.width == plain.width);
  REQUIRE(lit.height > plain.height);
  const int half = (plain.width - 8) / 2;
  const double bi = hotness(lit, 0, half, plain.height), mbi = hotness(lit, half + 8, lit.width, plain.height);
  INFO("BI " << bi << ", modified-BI " << mbi);
  CHECK(bi > mbi + 25);  // of 255: the bands along BI's faces are orange to red, modified-BI's stay blue
  // the legend: its bar's left end the scale's cold end, its right end the hot end (within 3/255)
  const int y = plain.height + (lit.height - plain.height) / 2;
  int x0 = 16;  // right of the "0"
  while (x0 < lit.width && lit.at(x0, y)[0] == 255) ++x0;  // the bar's cold end
  const std::uint8_t* cold = lit.at(x0, y);
  int x = lit.width - 1;
  while (x > 0 && !(lit.at(x, y)[0] > 200 && lit.at(x, y)[2] < 60)) --x;  // the bar's hot end, left of its value
  REQUIRE(x > x0 + 100);
  const Eigen::Vector3d c0 = mbi::pipeline::crease_color(0) * 255, c1 = mbi::pipeline::crease_color(1) * 255;
  for (int k = 0; k < 3; ++k) {
    CHECK(std::abs(cold[k] - c0(k)) < 12);
    CHECK(std::abs(lit.at(x, y)[k] - c1(k)) < 12);
  }
  // negative control: at rest (frame 0) nothing jumps, both panels the same cold colour
  const mbi::io::Image rest = mbi::io::read_png(mbi::io::frame_path(dir / "on" / "frame", 0, ".png"));
  CHECK(std::abs(hotness(rest, 0, half, plain.height) - hotness(rest, half + 8, rest.width, plain.height)) < 3);
  // off: the usual pictures (480 pixels high, no legend strip, the single-colour surface)
  CHECK(plain.height == 480);
  CHECK(std::abs(hotness(plain, 0, half, plain.height) - hotness(plain, half + 8, plain.width, plain.height)) < 3);
}
