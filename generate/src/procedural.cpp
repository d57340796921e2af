#include <mbi/error.hpp>
#include <mbi/generate/procedural.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace mbi::generate {
namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw mbi::Error(what);
}

// Lattice points of the box surface: index of lattice point (i, j, k) or -1 if interior.
struct SurfaceLattice {
  Eigen::Vector3i n;
  std::vector<int> index;
  int at(int i, int j, int k) const { return index[(static_cast<size_t>(k) * (n.y() + 1) + j) * (n.x() + 1) + i]; }
};

}  // namespace

void box_surface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n,
                 Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  require(n.minCoeff() >= 1, "a box needs cell counts >= 1");
  require((hi - lo).minCoeff() > 0, "a box needs max > min in every coordinate");
  SurfaceLattice L{n, std::vector<int>(static_cast<size_t>(n.x() + 1) * (n.y() + 1) * (n.z() + 1), -1)};
  std::vector<Eigen::Vector3d> pts;
  for (int k = 0; k <= n.z(); ++k)
    for (int j = 0; j <= n.y(); ++j)
      for (int i = 0; i <= n.x(); ++i) {
        const bool on = i == 0 || j == 0 || k == 0 || i == n.x() || j == n.y() || k == n.z();
        if (!on) continue;
        L.index[(static_cast<size_t>(k) * (n.y() + 1) + j) * (n.x() + 1) + i] = static_cast<int>(pts.size());
        const Eigen::Vector3d t(double(i) / n.x(), double(j) / n.y(), double(k) / n.z());
        pts.push_back(lo + (hi - lo).cwiseProduct(t));
      }
  V.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t p = 0; p < pts.size(); ++p) V.row(static_cast<Eigen::Index>(p)) = pts[p].transpose();

  std::vector<std::array<int, 3>> tris;
  // quad (a, b, c, d) counter-clockwise seen from outside -> two triangles
  auto quad = [&](int a, int b, int c, int d) {
    tris.push_back({a, b, c});
    tris.push_back({a, c, d});
  };
  // Faces perpendicular to each axis. For axis a with the other two (b, c) forming a
  // right-handed frame (a, b, c), the face at the max side has outward normal +a: the quad
  // (b, c) -> counter-clockwise in (b, c). At the min side, reverse.
  for (int axis = 0; axis < 3; ++axis) {
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      for (int jc = 0; jc < n[c]; ++jc)
        for (int jb = 0; jb < n[b]; ++jb) {
          auto id = [&](int db, int dc) {
            Eigen::Vector3i q;
            q[axis] = side ? n[axis] : 0;
            q[b] = jb + db;
            q[c] = jc + dc;
            return L.at(q.x(), q.y(), q.z());
          };
          if (side)
            quad(id(0, 0), id(1, 0), id(1, 1), id(0, 1));
          else
            quad(id(0, 0), id(0, 1), id(1, 1), id(1, 0));
        }
    }
  }
  F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t t = 0; t < tris.size(); ++t)
    for (int c = 0; c < 3; ++c) F(static_cast<Eigen::Index>(t), c) = tris[t][static_cast<size_t>(c)];
}

void box_tets(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n,
              Eigen::MatrixXd& V, Eigen::MatrixXi& T) {
  require(n.minCoeff() >= 1, "a box needs cell counts >= 1");
  require((hi - lo).minCoeff() > 0, "a box needs max > min in every coordinate");
  const int nx = n.x() + 1, ny = n.y() + 1, nz = n.z() + 1;
  V.resize(nx * ny * nz, 3);
  auto id = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Eigen::Vector3d t(double(i) / n.x(), double(j) / n.y(), double(k) / n.z());
        V.row(id(i, j, k)) = (lo + (hi - lo).cwiseProduct(t)).transpose();
      }
  // Kuhn split: 6 tets along the diagonal 0 -> 7, one per permutation of the axes.
  static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  T.resize(6 * n.x() * n.y() * n.z(), 4);
  int t = 0;
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i)
        for (const auto& p : perms) {
          Eigen::Vector3i c(i, j, k);
          std::array<int, 4> v;
          v[0] = id(c.x(), c.y(), c.z());
          for (int s = 0; s < 3; ++s) {
            c[p[s]] += 1;
            v[static_cast<size_t>(s) + 1] = id(c.x(), c.y(), c.z());
          }
          // orient positively
          const Eigen::Vector3d a = V.row(v[1]) - V.row(v[0]);
          const Eigen::Vector3d b = V.row(v[2]) - V.row(v[0]);
          const Eigen::Vector3d d = V.row(v[3]) - V.row(v[0]);
          if (a.cross(b).dot(d) < 0) std::swap(v[1], v[2]);
          T.row(t++) << v[0], v[1], v[2], v[3];
        }
}

void paper_bar_control(Eigen::MatrixXd& U, Eigen::MatrixXi& T) {
  const int layers = 7, per = 5;  // 4 corners (counter-clockwise) + centre
  const double length = 6.0;
  U.resize(layers * per, 3);
  const double cx[4] = {-0.5, 0.5, 0.5, -0.5}, cy[4] = {-0.5, -0.5, 0.5, 0.5};
  for (int l = 0; l < layers; ++l) {
    const double z = length * l / (layers - 1);
    for (int c = 0; c < 4; ++c) U.row(l * per + c) << cx[c], cy[c], z;
    U.row(l * per + 4) << 0.0, 0.0, z;
  }
  // Prism (a, b, c) x (a', b', c') split into 3 tets conformingly: each quad face is cut along
  // the diagonal through its smallest global index; the tets come from the vertex with the
  // smallest index (standard rule, consistent between neighbours).
  std::vector<std::array<int, 4>> tets;
  auto prism = [&](std::array<int, 3> bot, std::array<int, 3> top) {
    // rotate so that the smallest index among all six is bot[0] or top[0]
    int best = 0;
    for (int r = 0; r < 3; ++r)
      if (std::min(bot[r], top[r]) < std::min(bot[best], top[best])) best = r;
    std::rotate(bot.begin(), bot.begin() + best, bot.end());
    std::rotate(top.begin(), top.begin() + best, top.end());
    if (top[0] < bot[0]) std::swap(bot, top);  // now bot[0] is the smallest
    const int a = bot[0], b = bot[1], c = bot[2], a2 = top[0], b2 = top[1], c2 = top[2];
    // quads through a are cut at a (a-b2, a-c2); the quad (b, c, c2, b2) at its smallest vertex
    if (std::min(b, c2) < std::min(c, b2)) {
      tets.push_back({a, b, c, c2});
      tets.push_back({a, b, c2, b2});
    } else {
      tets.push_back({a, b, c, b2});
      tets.push_back({a, b2, c, c2});
    }
    tets.push_back({a, b2, c2, a2});
  };
  for (int l = 0; l + 1 < layers; ++l)
    for (int c = 0; c < 4; ++c) {
      const int o = l * per, o2 = (l + 1) * per;
      prism({o + 4, o + c, o + (c + 1) % 4}, {o2 + 4, o2 + c, o2 + (c + 1) % 4});
    }
  T.resize(static_cast<Eigen::Index>(tets.size()), 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    auto v = tets[t];
    const Eigen::Vector3d a = U.row(v[1]) - U.row(v[0]);
    const Eigen::Vector3d b = U.row(v[2]) - U.row(v[0]);
    const Eigen::Vector3d d = U.row(v[3]) - U.row(v[0]);
    if (a.cross(b).dot(d) < 0) std::swap(v[1], v[2]);
    T.row(static_cast<Eigen::Index>(t)) << v[0], v[1], v[2], v[3];
  }
}

void paper_bar_surface(Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  box_surface(Eigen::Vector3d(-0.5, -0.5, 0.0), Eigen::Vector3d(0.5, 0.5, 6.0),
              Eigen::Vector3i(30, 30, 180), V, F);
}

void cylinder_surface(double radius, double length, int around, int along, int cap_rings,
                      Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  require(radius > 0 && length > 0, "a cylinder needs radius and length > 0");
  require(around >= 3 && along >= 1 && cap_rings >= 1,
          "a cylinder needs 3 or more segments around and 1 or more along and in its caps");
  std::vector<Eigen::Vector3d> pts;
  std::vector<std::array<int, 3>> tris;
  const double pi = std::acos(-1.0);
  // side rings 0..along
  for (int r = 0; r <= along; ++r)
    for (int a = 0; a < around; ++a) {
      const double th = 2 * pi * a / around;
      pts.emplace_back(radius * std::cos(th), radius * std::sin(th), length * r / along);
    }
  auto ring = [&](int r, int a) { return r * around + ((a % around) + around) % around; };
  for (int r = 0; r < along; ++r)
    for (int a = 0; a < around; ++a) {
      tris.push_back({ring(r, a), ring(r, a + 1), ring(r + 1, a + 1)});
      tris.push_back({ring(r, a), ring(r + 1, a + 1), ring(r + 1, a)});
    }
  // caps: concentric rings (same angular resolution) down to a centre vertex
  for (int cap = 0; cap < 2; ++cap) {
    const double z = cap ? length : 0.0;
    const int outer_ring = cap ? along : 0;
    std::vector<int> prev(static_cast<size_t>(around));
    for (int a = 0; a < around; ++a) prev[static_cast<size_t>(a)] = ring(outer_ring, a);
    for (int c = 1; c < cap_rings; ++c) {
      const double rr = radius * (1.0 - double(c) / cap_rings);
      std::vector<int> cur(static_cast<size_t>(around));
      for (int a = 0; a < around; ++a) {
        const double th = 2 * pi * a / around;
        cur[static_cast<size_t>(a)] = static_cast<int>(pts.size());
        pts.emplace_back(rr * std::cos(th), rr * std::sin(th), z);
      }
      for (int a = 0; a < around; ++a) {
        const size_t a0 = static_cast<size_t>(a), a1 = static_cast<size_t>((a + 1) % around);
        if (cap) {
          tris.push_back({prev[a0], prev[a1], cur[a1]});
          tris.push_back({prev[a0], cur[a1], cur[a0]});
        } else {
          tris.push_back({prev[a0], cur[a1], prev[a1]});
          tris.push_back({prev[a0], cur[a0], cur[a1]});
        }
      }
      prev = cur;
    }
    const int centre = static_cast<int>(pts.size());
    pts.emplace_back(0.0, 0.0, z);
    for (int a = 0; a < around; ++a) {
      const size_t a0 = static_cast<size_t>(a), a1 = static_cast<size_t>((a + 1) % around);
      if (cap)
        tris.push_back({prev[a0], prev[a1], centre});
      else
        tris.push_back({prev[a1], prev[a0], centre});
    }
  }
  V.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t p = 0; p < pts.size(); ++p) V.row(static_cast<Eigen::Index>(p)) = pts[p].transpose();
  F.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t t = 0; t < tris.size(); ++t)
    F.row(static_cast<Eigen::Index>(t)) << tris[t][0], tris[t][1], tris[t][2];
}

void bumpy_sphere(double radius, int n, double bump, Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  require(radius > 0 && n >= 1, "a bumpy sphere needs radius > 0 and n > 0");
  require(bump >= 0 && bump < 0.5, "a bumpy sphere needs a bump in [0, 0.5)");
  box_surface(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1), Eigen::Vector3i::Constant(n), V, F);
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const Eigen::Vector3d d = V.row(i).normalized();
    const double r = 1.0 + bump * std::sin(5 * d.x()) * std::sin(6 * d.y()) * std::sin(7 * d.z());
    V.row(i) = (radius * r) * d.transpose();
  }
}

void grid_2d(double width, double height, int nx, int ny, Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  require(width > 0 && height > 0 && nx >= 1 && ny >= 1,
          "a 2D grid needs a positive size and 1 or more cells along each side");
  V.resize((nx + 1) * (ny + 1), 2);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) V.row(j * (nx + 1) + i) << width * i / nx, height * j / ny;
  F.resize(2 * nx * ny, 3);
  int t = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 2, d = a + nx + 1;
      F.row(t++) << a, b, c;
      F.row(t++) << a, c, d;
    }
}

Eigen::MatrixXd twist_bend(const Eigen::Ref<const Eigen::MatrixXd>& P, double cx, double cy,
                           double z0, double z1, double angle, double bend) {
  require(P.cols() == 3, "the twist needs points n x 3");
  require(z1 > z0, "the twist needs z1 > z0");
  Eigen::MatrixXd X = P;
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const double s = std::clamp((P(i, 2) - z0) / (z1 - z0), 0.0, 1.0);
    const double th = angle * s, c = std::cos(th), sn = std::sin(th);
    const double x = P(i, 0) - cx, y = P(i, 1) - cy;
    X(i, 0) = cx + c * x - sn * y + bend * s * s * (z1 - z0);
    X(i, 1) = cy + sn * x + c * y;
  }
  return X;
}

Eigen::MatrixXd twist_bend_jacobian(const Eigen::Ref<const Eigen::MatrixXd>& P, double cx,
                                    double cy, double z0, double z1, double angle, double bend) {
  require(P.cols() == 3, "the twist needs points n x 3");
  require(z1 > z0, "the twist needs z1 > z0");
  Eigen::MatrixXd J(3 * P.rows(), 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const double L = z1 - z0, t = (P(i, 2) - z0) / L;
    const double s = std::clamp(t, 0.0, 1.0), ds = t >= 0.0 && t <= 1.0 ? 1.0 / L : 0.0;
    const double th = angle * s, c = std::cos(th), sn = std::sin(th);
    const double x = P(i, 0) - cx, y = P(i, 1) - cy;
    J.middleRows(3 * i, 3) << c, -sn, (-sn * x - c * y) * angle * ds + 2 * bend * s * ds * L,
        sn, c, (c * x - sn * y) * angle * ds,
        0, 0, 1;
  }
  return J;
}

using io::Image;

Image test_pattern(int width, int height) {
  Image img(width, height);
  const double cx = 0.5 * width, cy = 0.5 * height;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const bool check = ((x / 32) + (y / 32)) % 2 == 0;
      const double r = std::hypot(x - cx, y - cy);
      const bool ring = std::fmod(r, 48.0) < 5.0;
      std::uint8_t* px = img.at(x, y);
      if (ring) {
        px[0] = 200, px[1] = 40, px[2] = 40;
      } else if (check) {
        px[0] = 60, px[1] = 90, px[2] = 160;
      } else {
        px[0] = 235, px[1] = 235, px[2] = 220;
      }
    }
  return img;
}

}  // namespace mbi::generate
