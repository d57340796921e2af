// The creases in colour (mbi/scenes/creases.hpp) and `mbi run`'s pictures with output.creases:
// the per-face jumps are the discontinuity table's energies per area; BI's panel is hotter than
// modified-BI's where the table says BI jumps more; at rest nothing glows (negative control);
// with the option off the pictures are the usual ones.
#include <catch2/catch.hpp>

#include <mbi/interp.hpp>
#include <mbi/io/io.hpp>
#include <mbi/scenes/creases.hpp>
#include <mbi/scenes/runner.hpp>

#include "common/files.hpp"
#include "common/grid_meshes.hpp"
#include "common/temp_dir.hpp"

#include <cmath>
#include <fstream>

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

TEST_CASE("creases: the face jumps are the discontinuity energies per area, a point on a face takes its jump",
          "[creases]") {
  const mbi::test::Mesh m = mbi::test::box_tet_mesh(2, 2, 2, Eigen::Vector3d(1, 1, 1));
  Eigen::MatrixXd X = m.U;
  for (Eigen::Index i = 0; i < X.rows(); ++i) X(i, 0) += 0.3 * std::sin(3 * m.U(i, 1)) * m.U(i, 2);  // a bend
  const mbi::interp::VertexMatrices Z = mbi::interp::VertexMatrices::Zero(X.size(), 3);
  const Creases creases(m.U, m.T);
  const Eigen::VectorXd j = creases.face_jumps(X, Z);
  const Eigen::VectorXd E = mbi::interp::face_discontinuity(m.U, m.T, X, Z);
  const Eigen::MatrixXi F = mbi::interp::interior_faces(m.T);
  REQUIRE(j.size() == F.rows());
  REQUIRE(j.maxCoeff() > 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = m.U.row(F(f, 0)), b = m.U.row(F(f, 1)), c = m.U.row(F(f, 2));
    CHECK(j(f) * j(f) * 0.5 * (b - a).cross(c - a).norm() == Approx(E(f)).epsilon(1e-12).margin(1e-15));
  }
  // dense points: the centroid of face 0 (on it), and an element's centroid (away from every face)
  const int e = F(0, 3);
  Eigen::MatrixXd P(2, 3);
  P.row(0) = (m.U.row(F(0, 0)) + m.U.row(F(0, 1)) + m.U.row(F(0, 2))) / 3;
  P.row(1) = (m.U.row(m.T(e, 0)) + m.U.row(m.T(e, 1)) + m.U.row(m.T(e, 2)) + m.U.row(m.T(e, 3))) / 4;
  const mbi::interp::Embedding emb = mbi::interp::embed(m.U, m.T, P);
  const Eigen::VectorXd v = creases.point_values(emb, j);
  CHECK(v(0) >= j(0) * (1 - 1e-9));  // on face 0: at least its jump (the largest of the faces it meets)
  CHECK(v(1) == 0);                   // barycentric 1/4 > kCreaseBand from every face
  CHECK(creases.near_faces(emb) == std::vector<bool>{true, false});
}

TEST_CASE("creases: the colour scale grows hotter (red minus blue) from 0 to 1", "[creases]") {
  double last = -2;
  for (int i = 0; i <= 20; ++i) {
    const Eigen::Vector3d c = crease_color(i / 20.0);
    CHECK(c(0) - c(2) > last);
    last = c(0) - c(2);
  }
  CHECK(crease_number(0) == "0");
  CHECK(crease_number(0.33896) == "0.339");
}

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
  const Eigen::Vector3d c0 = crease_color(0) * 255, c1 = crease_color(1) * 255;
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
