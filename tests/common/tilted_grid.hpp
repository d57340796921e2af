#pragma once
// A grid surface for picking tests (header-only, Eigen only): n x n squares of 0.7 x 0.3, 2
// triangles each, turned about (1, 1, 1) and moved off the origin, so that its vertices lie at
// coordinates binary floating point does not hold exactly: a ray through a shared vertex or
// edge lands a rounding error off the triangles' edges. kEye sees the grid from above.
#include "common/grid_meshes.hpp"

namespace mbi::test {

struct TiltedGrid {
  Eigen::MatrixXd V;  ///< (n+1)^2 x 3
  Eigen::MatrixXi F;  ///< 2 n^2 x 3
  int n = 0;
  Eigen::Vector3d at(int i, int j) const { return V.row(j * (n + 1) + i).transpose(); }
  /// The inner vertices, then the midpoints of the edges from each along x, y and the diagonal.
  std::vector<Eigen::Vector3d> shared_points() const {
    std::vector<Eigen::Vector3d> out;
    for (int j = 1; j < n; ++j)
      for (int i = 1; i < n; ++i)
        for (const Eigen::Vector3d& q : {at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)})
          out.push_back(q == at(i, j) ? q : Eigen::Vector3d(0.5 * (at(i, j) + q)));
    return out;
  }
  inline static const Eigen::Vector3d kEye{-1.3, 2.9, 3.1};
};

inline TiltedGrid tilted_grid(int n) {
  const Mesh flat = square_tri_mesh(n, n, Eigen::Vector2d(0.7, 0.3));
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 1, 1).normalized()).toRotationMatrix();
  TiltedGrid g{Eigen::MatrixXd(flat.U.rows(), 3), flat.T, n};
  for (Eigen::Index v = 0; v < flat.U.rows(); ++v)
    g.V.row(v) = (R * Eigen::Vector3d(flat.U(v, 0) + 0.1, flat.U(v, 1) - 0.3, 0.7)).transpose();
  return g;
}

}  // namespace mbi::test
