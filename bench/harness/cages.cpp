// Box cages, poses and point clouds of the harness (see cages.hpp).
#include "cages.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <utility>

namespace harness {

Cage box(int nx, int ny, int nz) {
  Cage c;
  c.cells = {nx, ny, nz};
  auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  c.U.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) c.U.row(id(i, j, k)) << i, j, k;
  // Kuhn split: each path through the cube's axes is one tetrahedron
  const int paths[6][2] = {{0, 1}, {0, 2}, {1, 0}, {1, 2}, {2, 0}, {2, 1}};
  c.T.resize(6 * nx * ny * nz, 4);
  int e = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : paths) {
          int at[3] = {i, j, k};
          int v[4];
          v[0] = id(at[0], at[1], at[2]);
          for (int s = 0; s < 3; ++s) {
            ++at[s < 2 ? p[s] : 3 - p[0] - p[1]];
            v[s + 1] = id(at[0], at[1], at[2]);
          }
          const Eigen::Vector3d a = c.U.row(v[1]) - c.U.row(v[0]), b = c.U.row(v[2]) - c.U.row(v[0]),
                                d = c.U.row(v[3]) - c.U.row(v[0]);
          if (a.cross(b).dot(d) < 0) std::swap(v[2], v[3]);
          c.T.row(e++) << v[0], v[1], v[2], v[3];
        }
  return c;
}

Eigen::MatrixXd pose(const Cage& c, double phase) {
  const double cx = 0.5 * c.cells.x(), cy = 0.5 * c.cells.y(), h = c.cells.z();
  Eigen::MatrixXd X = c.U;
  for (Eigen::Index v = 0; v < X.rows(); ++v) {
    const double t = c.U(v, 2) / h;
    const double a = phase * 1.2 * t;
    const double x = c.U(v, 0) - cx, y = c.U(v, 1) - cy;
    X(v, 0) = cx + std::cos(a) * x - std::sin(a) * y + phase * 0.1 * h * t * t;
    X(v, 1) = cy + std::sin(a) * x + std::cos(a) * y;
  }
  return X;
}

Eigen::MatrixXd cloud(const Cage& c, long long p) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(0.001, 0.999);
  Eigen::MatrixXd P(p, 3);
  for (long long i = 0; i < p; ++i)
    for (int a = 0; a < 3; ++a) P(i, a) = c.cells(a) * uni(rng);
  return P;
}

}  // namespace harness
