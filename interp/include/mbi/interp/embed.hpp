#pragma once
// Embedding of dense points in the control mesh: element + barycentric coordinates.
#include <mbi/interp/mesh.hpp>

#include <vector>

namespace mbi::interp {

struct Embedding {
  Eigen::VectorXi element;   ///< p, element containing (or nearest to) each point
  Eigen::MatrixXd bary;      ///< p x (d+1), barycentric coordinates in that element (sum 1)
  std::vector<int> outside;  ///< points outside every element, attached to the nearest one
                             ///< with extrapolated coordinates (some negative)
  std::vector<double> outside_distance;  ///< distance of each outside point to the mesh (P's units)
  double max_outside_distance = 0.0;  ///< largest distance of an outside point to the mesh
  /// (m (d+1)) x d: rows [e (d+1), e (d+1) + d] are basis_gradients(U, T, e). Filled by embed();
  /// evaluate() needs it for normals only (J = sum_k dx/dphi_k a_k^T, fact 6).
  Eigen::MatrixXd gradients;
  int dim() const { return static_cast<int>(bary.cols()) - 1; }
  int size() const { return static_cast<int>(element.size()); }
};

/// Locates every row of P (p x d) in the control mesh (U, T) with a uniform-grid acceleration
/// structure (no loop over all elements per point). A point is inside an element when all its
/// coordinates are >= -tol (tol = 1e-9). Scale-free: the search runs on coordinates moved to
/// the centre of U's bounding box and divided by its largest extent s, so meshes of any size
/// (1e-100 to 1e100) at any offset embed alike; distances and gradients are in P's units.
/// Throws Error on a non-finite point (naming it), on a point farther than 1e12 s from the
/// mesh's bounding box (naming it: extrapolating from there means nothing), on a control mesh of
/// zero extent or too small for its gradients to be finite, or on a dimension mismatch.
Embedding embed(const Eigen::Ref<const Eigen::MatrixXd>& U,
                const Eigen::Ref<const Eigen::MatrixXi>& T,
                const Eigen::Ref<const Eigen::MatrixXd>& P);

/// Rest positions reproduced from an embedding: sum_k bary(p,k) * U(T(e,k)). p x d.
Eigen::MatrixXd embedded_positions(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                   const Eigen::Ref<const Eigen::MatrixXi>& T,
                                   const Embedding& emb);

}  // namespace mbi::interp
