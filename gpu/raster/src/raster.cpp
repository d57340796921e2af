#include <mbi/raster/raster.hpp>

#include <Eigen/Geometry>


#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace mbi::raster {

using io::Image;
namespace {

struct Projector {
  Eigen::Vector3d right, up, fwd;
  double scale = 1, cx = 0, cy = 0, aspect = 1;
  int w = 0, h = 0;
  Projector(const View& v, int width, int height) : w(width), h(height) {
    fwd = v.direction.normalized();
    right = fwd.cross(v.up).normalized();
    up = right.cross(fwd);
    // frame the 8 corners of the bounds
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d p((c & 1) ? v.bounds_max.x() : v.bounds_min.x(),
                              (c & 2) ? v.bounds_max.y() : v.bounds_min.y(),
                              (c & 4) ? v.bounds_max.z() : v.bounds_min.z());
      x0 = std::min(x0, p.dot(right));
      x1 = std::max(x1, p.dot(right));
      y0 = std::min(y0, p.dot(up));
      y1 = std::max(y1, p.dot(up));
    }
    const double sx = (x1 - x0) * (1 + 2 * v.margin), sy = (y1 - y0) * (1 + 2 * v.margin);
    aspect = sx / std::max(sy, 1e-300);
    scale = std::min(width / std::max(sx, 1e-300), height / std::max(sy, 1e-300));
    cx = 0.5 * (x0 + x1);
    cy = 0.5 * (y0 + y1);
  }
  // screen x (right), y (down), depth (larger = farther)
  Eigen::Vector3d operator()(const Eigen::Vector3d& p) const {
    return {0.5 * w + (p.dot(right) - cx) * scale, 0.5 * h - (p.dot(up) - cy) * scale, p.dot(fwd)};
  }
};

double edge_fn(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
}

// Calls fn(x, y, w0, w1, w2) for every pixel centre inside the screen triangle (a, b, c).
template <typename Fn>
void raster_triangle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                     int w, int h, Fn&& fn) {
  const double area = edge_fn(a, b, c);
  if (std::abs(area) < 1e-12) return;
  const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
  const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
  const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
  const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const Eigen::Vector2d p(x + 0.5, y + 0.5);
      const double w0 = edge_fn(b, c, p) / area, w1 = edge_fn(c, a, p) / area;
      const double w2 = 1.0 - w0 - w1;
      if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
      fn(x, y, w0, w1, w2);
    }
}

std::uint8_t to_byte(double v) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(v * 255.0), 0L, 255L));
}

}  // namespace


double view_aspect(const View& view) { return Projector(view, 1, 1).aspect; }

View frame_points(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Vector3d& direction,
                  const Eigen::Vector3d& up) {
  View v;
  v.direction = direction;
  v.up = up;
  v.bounds_min = V.colwise().minCoeff().transpose();
  v.bounds_max = V.colwise().maxCoeff().transpose();
  return v;
}

Eigen::MatrixXd vertex_normals(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F) {
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(V.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n.transpose();
  }
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const double l = N.row(i).norm();
    if (l > 0) N.row(i) /= l;
  }
  return N;
}

namespace {

void check_mesh(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F) {
  if (V.cols() != 3 || F.cols() != 3) throw std::invalid_argument("the mesh to render needs n x 3, f x 3");
  if (F.size() > 0 && (F.minCoeff() < 0 || F.maxCoeff() >= V.rows()))
    throw std::invalid_argument("the mesh to render indexes vertices outside its " + std::to_string(V.rows()));
}

// Draws V, F into img where it is nearer than `depth` (and writes its depth there).
void draw_shaded(Image& img, std::vector<double>& depth, const Projector& proj, const Eigen::Ref<const Eigen::MatrixXd>& V,
                 const Eigen::Ref<const Eigen::MatrixXi>& F, const Eigen::Vector3d& color, bool shaded = true) {
  const int width = img.width, height = img.height;
  const Eigen::MatrixXd N = vertex_normals(V, F);
  Eigen::MatrixXd S(V.rows(), 3);  // screen coordinates
  for (Eigen::Index i = 0; i < V.rows(); ++i) S.row(i) = proj(V.row(i).transpose()).transpose();
  const Eigen::Vector3d light = -proj.fwd;  // headlight
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int i0 = F(f, 0), i1 = F(f, 1), i2 = F(f, 2);
    raster_triangle(S.row(i0).head<2>().transpose(), S.row(i1).head<2>().transpose(),
                    S.row(i2).head<2>().transpose(), width, height,
                    [&](int x, int y, double w0, double w1, double w2) {
                      const double z = w0 * S(i0, 2) + w1 * S(i1, 2) + w2 * S(i2, 2);
                      double& zb = depth[static_cast<size_t>(y) * width + x];
                      if (z >= zb) return;
                      zb = z;
                      std::uint8_t* px = img.at(x, y);
                      if (!shaded) {
                        for (int c = 0; c < 3; ++c) px[c] = to_byte(color[c]);
                        return;
                      }
                      Eigen::Vector3d n = w0 * N.row(i0) + w1 * N.row(i1) + w2 * N.row(i2);
                      n.normalize();
                      const double lam = std::abs(n.dot(light));
                      const double spec = std::pow(lam, 40.0) * 0.25;
                      for (int c = 0; c < 3; ++c)
                        px[c] = to_byte(color[c] * (0.18 + 0.82 * lam) + spec);
                    });
  }
}

}  // namespace

Image render_mesh(const Eigen::Ref<const Eigen::MatrixXd>& V,
                  const Eigen::Ref<const Eigen::MatrixXi>& F, const View& view, int width,
                  int height, const Eigen::Vector3d& color, const std::vector<Solid>& solids) {
  check_mesh(V, F);
  for (const Solid& s : solids) check_mesh(s.V, s.F);
  Image img(width, height, {255, 255, 255});
  const Projector proj(view, width, height);
  std::vector<double> depth(static_cast<size_t>(width) * height,
                            std::numeric_limits<double>::infinity());
  draw_shaded(img, depth, proj, V, F, color);
  for (const Solid& s : solids) draw_shaded(img, depth, proj, s.V, s.F, s.color, s.shaded);
  return img;
}

void draw_edges(Image& img, const Eigen::Ref<const Eigen::MatrixXd>& U,
                const Eigen::Ref<const Eigen::MatrixXi>& T, const View& view,
                const Eigen::Vector3i& rgb) {
  const Projector proj(view, img.width, img.height);
  for (Eigen::Index e = 0; e < T.rows(); ++e)
    for (int a = 0; a < T.cols(); ++a)
      for (int b = a + 1; b < T.cols(); ++b) {
        const Eigen::Vector3d p = proj(U.row(T(e, a)).transpose());
        const Eigen::Vector3d q = proj(U.row(T(e, b)).transpose());
        const int steps = static_cast<int>(std::ceil((q - p).head<2>().norm())) + 1;
        for (int s = 0; s <= steps; ++s) {
          const Eigen::Vector3d r = p + (q - p) * (double(s) / steps);
          const int x = static_cast<int>(r.x()), y = static_cast<int>(r.y());
          if (x < 0 || y < 0 || x >= img.width || y >= img.height) continue;
          std::uint8_t* px = img.at(x, y);
          for (int c = 0; c < 3; ++c)
            px[c] = static_cast<std::uint8_t>((px[c] + rgb[c]) / 2);
        }
      }
}

Image warp_image(const Image& src, const Eigen::Ref<const Eigen::MatrixXd>& rest,
                 const Eigen::Ref<const Eigen::MatrixXd>& deformed,
                 const Eigen::Ref<const Eigen::MatrixXi>& F, int out_w, int out_h) {
  if (rest.cols() != 2 || deformed.cols() != 2 || rest.rows() != deformed.rows() || F.cols() != 3)
    throw std::invalid_argument("an image warp needs rest and deformed n x 2 and F f x 3");
  Image out(out_w, out_h, {255, 255, 255});
  auto sample = [&](double x, double y, int c) {
    x = std::clamp(x - 0.5, 0.0, src.width - 1.0);
    y = std::clamp(y - 0.5, 0.0, src.height - 1.0);
    const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
    const int x1 = std::min(x0 + 1, src.width - 1), y1 = std::min(y0 + 1, src.height - 1);
    const double fx = x - x0, fy = y - y0;
    return (1 - fy) * ((1 - fx) * src.at(x0, y0)[c] + fx * src.at(x1, y0)[c]) +
           fy * ((1 - fx) * src.at(x0, y1)[c] + fx * src.at(x1, y1)[c]);
  };
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const int i0 = F(f, 0), i1 = F(f, 1), i2 = F(f, 2);
    raster_triangle(deformed.row(i0).transpose(), deformed.row(i1).transpose(),
                    deformed.row(i2).transpose(), out_w, out_h,
                    [&](int x, int y, double w0, double w1, double w2) {
                      const Eigen::Vector2d t =
                          w0 * rest.row(i0) + w1 * rest.row(i1) + w2 * rest.row(i2);
                      std::uint8_t* px = out.at(x, y);
                      for (int c = 0; c < 3; ++c)
                        px[c] = static_cast<std::uint8_t>(std::clamp(sample(t.x(), t.y(), c), 0.0, 255.0));
                    });
  }
  return out;
}

Image side_by_side(const std::vector<Image>& images, int gap) {
  if (images.empty()) throw std::invalid_argument("no images to put side by side");
  int w = 0, h = 0;
  for (const Image& i : images) {
    w += i.width;
    h = std::max(h, i.height);
  }
  w += gap * static_cast<int>(images.size() - 1);
  Image out(w, h, {255, 255, 255});
  int x0 = 0;
  for (const Image& i : images) {
    for (int y = 0; y < i.height; ++y)
      std::copy(i.at(0, y), i.at(0, y) + 3 * i.width, out.at(x0, y));
    x0 += i.width + gap;
  }
  return out;
}




}  // namespace mbi::raster
