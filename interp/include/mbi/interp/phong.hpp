#pragma once
// Phong deformation (D. L. James, "Phong Deformation: A Better C0 Interpolant for Embedded
// Deformation", ACM TOG 39(4), 2020) as modified-BI's kernel with a closed-form M.
//
// Per element e: F_e = D_s D_m^-1 (columns x_k - x_0 and u_k - u_0, k = 1..d). Per control
// vertex i, over its incident elements e, with r_e = (rest centroid of e) - u_i, rh_e = r_e/|r_e|:
//
//   lambda_i = -(I + sum_e rh_e rh_e^T)^-1 sum_e rh_e
//   w_e      ~ (1 + lambda_i . rh_e) / |r_e|,   normalised to sum_e w_e = 1
//   F_i      = sum_e w_e F_e
//
// (Shepard weights with a regularised linear-precision correction; the unnormalised weights
// satisfy sum_e (1 + lambda_i . rh_e) rh_e = -lambda_i.) Phong's interpolant
// f = (f_C + f_V) / 2, with f_C = BI and f_V = sum_i phi_i (x_i + F_i (u - u_i)), is exactly
// modified-BI's x(u) = sum_i phi_i (x_i + M_i (u - u_i)) with M_i = F_i / 2 (because
// sum_i phi_i = 1 and sum_i phi_i u_i = u). So Phong is evaluated by the same Bezier kernel
// (method.md fact 5) and needs no factorisation: the weights depend on the rest mesh only and are
// computed once; per frame M(X) costs one pass over the elements.
//
// Properties: F_i = A for every affine deformation x = A u + b (weights sum to 1), so Phong
// reproduces affine maps exactly; x(u_k) = x_k (interpolation), like every M.
#include <mbi/interp/modified_bi.hpp>

#include <vector>

namespace mbi::interp {

class Phong {
 public:
  /// Precomputes the vertex weights for rest mesh U (n x d, d = 2 or 3), T (m x (d+1)).
  /// Validates the mesh (throws Error naming the element). Cost O(m d^3).
  Phong(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T);

  int dim() const { return static_cast<int>(U_.cols()); }
  int vertices() const { return static_cast<int>(U_.rows()); }
  int elements() const { return static_cast<int>(T_.rows()); }

  /// Per-element deformation gradients F_e = D_s D_m^-1 for deformed positions X (n x d):
  /// (m d) x d, rows [e d, e d + d) hold F_e. Throws Error on a size mismatch or NaN.
  Eigen::MatrixXd element_gradients(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// Per-vertex deformation gradients F_i = sum_e w_e F_e: (n d) x d, rows [i d, i d + d) hold
  /// F_i; 0 for a vertex used by no element.
  Eigen::MatrixXd vertex_gradients(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// Phong's M: M_i = F_i / 2, (n d) x d as in ModifiedBI::solve().
  VertexMatrices M(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// The same into caller memory M ((n d) x d already, Error otherwise); its temporaries are
  /// kept per thread, so after the first call on a thread it allocates nothing of the mesh's size.
  void M(const Eigen::Ref<const Eigen::MatrixXd>& X, MatrixOut M) const;

  /// The transpose of M(), which is linear in X: dL/dX (n x d) from G = dL/dM ((n d) x d).
  /// Throws Error on a size mismatch or NaN.
  Eigen::MatrixXd M_transpose(const VertexMatrices& G) const;
  /// The same into caller memory GX (n x d already).
  void M_transpose(const Eigen::Ref<const VertexMatrices>& G, Eigen::Ref<Eigen::MatrixXd> GX) const;

  /// Weight w_e of element e at vertex i, for the incidences of vertex i in order:
  /// incident_elements(i)[k] has weight weights(i)[k]. The weights of a vertex sum to 1.
  const std::vector<int>& incident_elements(int i) const { return elements_of_[static_cast<size_t>(i)]; }
  const std::vector<double>& weights(int i) const { return weights_[static_cast<size_t>(i)]; }
  /// lambda_i (d) of vertex i, the linear-precision correction (0 for an unused vertex).
  Eigen::VectorXd correction(int i) const { return lambda_.row(i).transpose(); }
  /// Vertices whose corrected weights did not have a positive sum and fell back to plain
  /// Shepard weights w_e ~ 1/|r_e| (none on the meshes we have seen; reported for honesty).
  int fallback_vertices() const { return fallback_; }

  const Eigen::MatrixXd& rest_positions() const { return U_; }
  const Eigen::MatrixXi& elements_matrix() const { return T_; }

 private:
  void element_gradients(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::MatrixXd& F) const;
  void vertex_gradients(const Eigen::MatrixXd& Fe, MatrixOut F) const;
  Eigen::MatrixXd U_;
  Eigen::MatrixXi T_;
  Eigen::MatrixXd Dm_inv_;  // (m d) x d, rows [e d, e d + d) hold D_m^-1 of element e
  std::vector<std::vector<int>> elements_of_;
  std::vector<std::vector<double>> weights_;
  Eigen::MatrixXd lambda_;  // n x d
  int fallback_ = 0;
};

}  // namespace mbi::interp
