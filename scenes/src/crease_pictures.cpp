// Per-vertex coloured surfaces and the legend of `output.creases` pictures.
#include "crease_pictures.hpp"

#include <mbi/io/io.hpp>
#include <mbi/pipeline/creases.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace mbi::scenes {
namespace {

// raster::render_mesh's orthographic framing: screen x right, y down, depth along the view.
struct Projector {
  Eigen::Vector3d right, up, fwd;
  double scale = 1, cx = 0, cy = 0;
  int w, h;
  Projector(const raster::View& v, int width, int height) : w(width), h(height) {
    fwd = v.direction.normalized();
    right = fwd.cross(v.up).normalized();
    up = right.cross(fwd);
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d p((c & 1) ? v.bounds_max.x() : v.bounds_min.x(), (c & 2) ? v.bounds_max.y() : v.bounds_min.y(),
                              (c & 4) ? v.bounds_max.z() : v.bounds_min.z());
      x0 = std::min(x0, p.dot(right)), x1 = std::max(x1, p.dot(right));
      y0 = std::min(y0, p.dot(up)), y1 = std::max(y1, p.dot(up));
    }
    const double sx = (x1 - x0) * (1 + 2 * v.margin), sy = (y1 - y0) * (1 + 2 * v.margin);
    scale = std::min(width / std::max(sx, 1e-300), height / std::max(sy, 1e-300));
    cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  }
  Eigen::Vector3d operator()(const Eigen::Vector3d& p) const {
    return {0.5 * w + (p.dot(right) - cx) * scale, 0.5 * h - (p.dot(up) - cy) * scale, p.dot(fwd)};
  }
};

double edge(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double x, double y) {
  return (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
}

std::uint8_t to_byte(double v) { return static_cast<std::uint8_t>(std::clamp(std::lround(v * 255.0), 0L, 255L)); }

// 3 x 5 glyphs of the legend's numbers, rows top to bottom, 3 bits a row (left bit first).
const char* glyph(char c) {
  static const char* digits[10] = {"111101101101111", "010110010010111", "111001111100111", "111001111001111",
                                   "101101111001001", "111100111001111", "111100111101111", "111001001001001",
                                   "111101111101111", "111101111001111"};
  if (c >= '0' && c <= '9') return digits[c - '0'];
  if (c == '.') return "000000000000010";
  if (c == '-') return "000000111000000";
  if (c == '+') return "000010111010000";
  if (c == 'e') return "000111101110011";
  return "000000000000000";
}

void text(io::Image& img, int x, int y, const std::string& s, int px) {
  for (char c : s) {
    const char* g = glyph(c);
    for (int r = 0; r < 5; ++r)
      for (int q = 0; q < 3; ++q)
        if (g[r * 3 + q] == '1')
          for (int dy = 0; dy < px; ++dy)
            for (int dx = 0; dx < px; ++dx) {
              const int X = x + q * px + dx, Y = y + r * px + dy;
              if (X >= 0 && Y >= 0 && X < img.width && Y < img.height) std::fill_n(img.at(X, Y), 3, std::uint8_t{30});
            }
    x += 4 * px;
  }
}

}  // namespace

io::Image render_colored(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F,
                         const Eigen::Ref<const Eigen::MatrixXd>& C, const raster::View& view, int width, int height) {
  io::Image img(width, height, {255, 255, 255});
  const Projector proj(view, width, height);
  const Eigen::MatrixXd N = io::vertex_normals(V, F);
  std::vector<Eigen::Vector3d> S(static_cast<size_t>(V.rows()));
  for (Eigen::Index i = 0; i < V.rows(); ++i) S[static_cast<size_t>(i)] = proj(V.row(i).transpose());
  std::vector<double> depth(static_cast<size_t>(width) * height, std::numeric_limits<double>::infinity());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int i[3] = {F(f, 0), F(f, 1), F(f, 2)};
    const Eigen::Vector3d &a = S[static_cast<size_t>(i[0])], &b = S[static_cast<size_t>(i[1])], &c = S[static_cast<size_t>(i[2])];
    const double area = edge(a, b, c.x(), c.y());
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double w0 = edge(b, c, x + 0.5, y + 0.5) / area, w1 = edge(c, a, x + 0.5, y + 0.5) / area, w2 = 1 - w0 - w1;
        if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
        const double z = w0 * a.z() + w1 * b.z() + w2 * c.z();
        double& zb = depth[static_cast<size_t>(y) * width + x];
        if (z >= zb) continue;
        zb = z;
        const Eigen::Vector3d n = (w0 * N.row(i[0]) + w1 * N.row(i[1]) + w2 * N.row(i[2])).normalized().transpose();
        const Eigen::Vector3d col = (w0 * C.row(i[0]) + w1 * C.row(i[1]) + w2 * C.row(i[2])).transpose();
        const double lam = std::abs(n.dot(proj.fwd));
        std::uint8_t* px = img.at(x, y);
        for (int k = 0; k < 3; ++k) px[k] = to_byte(col[k] * (0.25 + 0.75 * lam));
      }
  }
  return img;
}

io::Image crease_legend(int width, double top) {
  const int px = 2, h = 5 * px + 18;
  io::Image img(std::max(width, 1), h, {255, 255, 255});
  const std::string hi = pipeline::crease_number(top);
  const int bar0 = 8 + 4 * px + 6, bar1 = std::max(bar0 + 1, std::min(width - 8 - 4 * px * static_cast<int>(hi.size()) - 6, bar0 + 320));
  for (int x = bar0; x < bar1; ++x) {
    const Eigen::Vector3d c = pipeline::crease_color(static_cast<double>(x - bar0) / std::max(bar1 - bar0 - 1, 1));
    for (int y = 6; y < h - 6; ++y)
      for (int k = 0; k < 3; ++k) img.at(x, y)[k] = to_byte(c[k]);
  }
  text(img, 8, (h - 5 * px) / 2, "0", px);
  text(img, bar1 + 6, (h - 5 * px) / 2, hi, px);
  return img;
}

io::Image stack(const io::Image& top, const io::Image& bottom) {
  io::Image img(std::max(top.width, bottom.width), top.height + bottom.height, {255, 255, 255});
  for (int y = 0; y < top.height; ++y) std::copy_n(top.at(0, y), 3 * top.width, img.at(0, y));
  for (int y = 0; y < bottom.height; ++y) std::copy_n(bottom.at(0, y), 3 * bottom.width, img.at(0, top.height + y));
  return img;
}

}  // namespace mbi::scenes
