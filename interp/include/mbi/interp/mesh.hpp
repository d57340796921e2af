#pragma once
// Control-mesh topology helpers shared by the whole interp library.
//
// Conventions (all of mbi):
//   U : n x d   rest positions of the control vertices (d = 2 or 3)
//   T : m x (d+1) element vertex indices (triangles in 2D, tetrahedra in 3D), 0-based
//   X : n x d   deformed positions of the control vertices
#include <mbi/error.hpp>

#include <Eigen/Core>
#include <stdexcept>
#include <string>

namespace mbi::interp {

/// Every error the library reports. The message names the element, face, point or argument.
class Error : public mbi::Error {
 public:
  using mbi::Error::Error;
};

/// Checks that U is n x d with d in {2,3}, finite, and T is m x (d+1) with indices in [0,n),
/// no repeated index and no degenerate element (|volume| <= tol * h^d, h = mean edge length).
/// Throws Error naming the first offending element / vertex.
void validate_mesh(const Eigen::Ref<const Eigen::MatrixXd>& U,
                   const Eigen::Ref<const Eigen::MatrixXi>& T, double rel_tol = 1e-12);

/// Signed volume (3D) or area (2D) of element e.
double element_volume(const Eigen::Ref<const Eigen::MatrixXd>& U,
                      const Eigen::Ref<const Eigen::MatrixXi>& T, int e);

/// Interior faces: F x (d + 2) rows [v_0 .. v_{d-1}, e_left, e_right], faces shared by two
/// elements (sorted vertex indices), each face once, deterministic order.
Eigen::MatrixXi interior_faces(const Eigen::Ref<const Eigen::MatrixXi>& T);

/// Boundary faces: B x d vertex indices (faces used by exactly one element), oriented outward.
Eigen::MatrixXi boundary_faces(const Eigen::Ref<const Eigen::MatrixXd>& U,
                               const Eigen::Ref<const Eigen::MatrixXi>& T);

/// Marks vertices on the boundary (size n, 1 = boundary).
Eigen::VectorXi boundary_vertices(int n, const Eigen::Ref<const Eigen::MatrixXi>& T);

/// Gradients a_i of the barycentric basis of element e: (d+1) x d, row i = a_i^T.
Eigen::MatrixXd basis_gradients(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                const Eigen::Ref<const Eigen::MatrixXi>& T, int e);

}  // namespace mbi::interp
