#pragma once
// Shared fixtures for the interp tests.
#include <mbi/interp.hpp>

#include "common/grid_meshes.hpp"

#include <random>

namespace mbi::test {

/// Jittered structured mesh in [0,1]^d: 3x3x3 cells (3D) or 5x4 cells (2D).
inline Mesh jittered_mesh(int d, unsigned seed = 1) {
  Mesh M = d == 3 ? box_tet_mesh(3, 3, 3) : square_tri_mesh(5, 4);
  jitter(M, 0.2, d == 3 ? 1.0 / 3 : 0.25, seed);
  return M;
}

/// A smooth nonlinear deformation of a d-dimensional point set (bend + twist + stretch).
inline Eigen::MatrixXd smooth_deform(const Eigen::MatrixXd& U, double amount = 0.3) {
  Eigen::MatrixXd X = U;
  for (Eigen::Index i = 0; i < U.rows(); ++i) {
    const double x = U(i, 0), y = U(i, 1);
    if (U.cols() == 3) {
      const double z = U(i, 2);
      X(i, 0) = x + amount * std::sin(1.3 * y + 0.4 * z);
      X(i, 1) = y + amount * std::cos(1.1 * x) * z;
      X(i, 2) = z + amount * x * x - 0.2 * amount * y;
    } else {
      X(i, 0) = x + amount * std::sin(1.7 * y);
      X(i, 1) = y + amount * x * x;
    }
  }
  return X;
}

inline Eigen::MatrixXd random_matrix(Eigen::Index r, Eigen::Index c, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  Eigen::MatrixXd A(r, c);
  for (Eigen::Index i = 0; i < r; ++i)
    for (Eigen::Index j = 0; j < c; ++j) A(i, j) = uni(rng);
  return A;
}

/// Random points inside element e (uniform barycentric sampling), as bary coordinates.
inline Eigen::VectorXd random_bary(int d, std::mt19937& rng) {
  std::exponential_distribution<double> ex(1.0);
  Eigen::VectorXd b(d + 1);
  for (int k = 0; k <= d; ++k) b(k) = ex(rng);
  return b / b.sum();
}

inline Eigen::VectorXd point_of(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T, int e,
                                const Eigen::VectorXd& b) {
  Eigen::VectorXd u = Eigen::VectorXd::Zero(U.cols());
  for (Eigen::Index k = 0; k < T.cols(); ++k) u += b(k) * U.row(T(e, k)).transpose();
  return u;
}

/// Per-component unknown vector m_c (d n) from VertexMatrices: entry i d + r = M_i(c, r).
inline Eigen::VectorXd component(const Eigen::MatrixXd& M, int d, int c) {
  const Eigen::Index n = M.rows() / d;
  Eigen::VectorXd m(n * d);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int r = 0; r < d; ++r) m(i * d + r) = M(i * d + c, r);
  return m;
}

}  // namespace mbi::test
