#pragma once
// Small structured test meshes (header-only, Eigen only, no mbi library needed).
//   box_tet_mesh:   (nx ny nz) cells of a box, each hex split into 6 tets (conforming)
//   square_tri_mesh:(nx ny) cells of a rectangle, each square split into 2 triangles
//   jitter:         moves interior vertices (not on the bounding box) randomly
//   random_rotation: a random proper rotation (d x d)
//   twist_bend:     smooth twist about the bar's long (x) axis plus a mild bend
// All elements are positively oriented (signed volume > 0).
#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <random>
#include <utility>

namespace mbi::test {

struct Mesh {
  Eigen::MatrixXd U;  ///< n x d rest positions
  Eigen::MatrixXi T;  ///< m x (d+1) elements
};

/// Box [0, size.x] x [0, size.y] x [0, size.z] with nx*ny*nz cells, 6 tets per cell (Kuhn split
/// along the main diagonal, so neighbouring cells share faces exactly).
inline Mesh box_tet_mesh(int nx, int ny, int nz, const Eigen::Vector3d& size = Eigen::Vector3d::Ones()) {
  Mesh M;
  auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  M.U.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        M.U.row(id(i, j, k)) << size.x() * i / nx, size.y() * j / ny, size.z() * k / nz;
  static const std::array<std::array<int, 3>, 6> perms{
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  M.T.resize(6 * nx * ny * nz, 4);
  int t = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : perms) {
          std::array<int, 3> c{i, j, k};
          std::array<int, 4> v{};
          v[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            v[s + 1] = id(c[0], c[1], c[2]);
          }
          Eigen::Matrix3d E;
          for (int s = 0; s < 3; ++s) E.col(s) = (M.U.row(v[s + 1]) - M.U.row(v[0])).transpose();
          if (E.determinant() < 0) std::swap(v[2], v[3]);
          M.T.row(t++) << v[0], v[1], v[2], v[3];
        }
  return M;
}

/// Rectangle [0, size.x] x [0, size.y] with nx*ny squares, each split into 2 triangles.
inline Mesh square_tri_mesh(int nx, int ny, const Eigen::Vector2d& size = Eigen::Vector2d::Ones()) {
  Mesh M;
  auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  M.U.resize((nx + 1) * (ny + 1), 2);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) M.U.row(id(i, j)) << size.x() * i / nx, size.y() * j / ny;
  M.T.resize(2 * nx * ny, 3);
  int t = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      M.T.row(t++) << id(i, j), id(i + 1, j), id(i + 1, j + 1);
      M.T.row(t++) << id(i, j), id(i + 1, j + 1), id(i, j + 1);
    }
  return M;
}

/// Moves every vertex strictly inside the bounding box by up to `amount` times the smallest
/// cell size h (uniform in [-amount h, amount h]^d). amount < 0.25 keeps elements valid.
inline void jitter(Mesh& M, double amount, double h, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const Eigen::RowVectorXd lo = M.U.colwise().minCoeff(), hi = M.U.colwise().maxCoeff();
  for (Eigen::Index i = 0; i < M.U.rows(); ++i) {
    bool interior = true;
    for (Eigen::Index c = 0; c < M.U.cols(); ++c)
      interior = interior && M.U(i, c) > lo(c) + 1e-12 && M.U(i, c) < hi(c) - 1e-12;
    if (!interior) continue;
    for (Eigen::Index c = 0; c < M.U.cols(); ++c) M.U(i, c) += amount * h * uni(rng);
  }
}

/// Random rotation (det +1), d = 2 or 3.
inline Eigen::MatrixXd random_rotation(int d, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd A(d, d);
  for (int i = 0; i < d; ++i)
    for (int j = 0; j < d; ++j) A(i, j) = g(rng);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  Eigen::MatrixXd Q = qr.householderQ();
  if (Q.determinant() < 0) Q.col(0) *= -1;
  return Q;
}

/// Twists a bar lying along x (length L = max x) by `twist` radians about the line through the
/// cross-section centre (y, z = cy, cz), linearly in x, then bends it: z += bend * (x / L)^2 * L.
inline Eigen::MatrixXd twist_bend(const Eigen::MatrixXd& U, double twist, double bend) {
  const double L = U.col(0).maxCoeff();
  const double cy = 0.5 * (U.col(1).minCoeff() + U.col(1).maxCoeff());
  const double cz = 0.5 * (U.col(2).minCoeff() + U.col(2).maxCoeff());
  Eigen::MatrixXd X = U;
  for (Eigen::Index i = 0; i < U.rows(); ++i) {
    const double s = U(i, 0) / L;
    const double a = twist * s;
    const double y = U(i, 1) - cy, z = U(i, 2) - cz;
    X(i, 1) = cy + std::cos(a) * y - std::sin(a) * z;
    X(i, 2) = cz + std::sin(a) * y + std::cos(a) * z + bend * s * s * L;
  }
  return X;
}

}  // namespace mbi::test
