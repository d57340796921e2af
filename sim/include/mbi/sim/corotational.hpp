#pragma once
// Co-rotational linear elasticity on linear tetrahedra, layered as in Bartels:
//   energy density (F -> psi, P)  ->  one element  ->  the assembled mesh.
//
// Conventions (all of mbi::sim):
//   U : n x 3  rest positions of the nodes (m)
//   T : m x 4  tetrahedra, 0-based node indices; either orientation is accepted
//   X : n x 3  deformed positions (m)
//   Node forces are n x 3 (N) and are the NEGATIVE gradient of the elastic energy.
//   Global vectors and matrices order the unknowns node-major: dof 3 i + c = node i, axis c.
//   Stiffness matrices are the (approximate or exact) Hessian of the energy: 3n x 3n, symmetric
//   positive semi-definite for the warped stiffness, in N/m.
//
// The co-rotated energy density is
//   psi(F) = mu ||S - I||_F^2 + lambda/2 tr(S - I)^2,   F = R S,
// with R the proper rotation of F (det R = +1 also when det F <= 0: the singular vector of the
// smallest singular value is flipped, Irving et al. 2004). Its first Piola stress
//   P = 2 mu (F - R) + lambda tr(R^T F - I) R
// is exactly the Mueller-Gross element force f = -R K (R^T x - u) written per element, so the
// forces are the exact negative gradient of the energy; the warped stiffness R K R^T drops the
// derivative of R (it is exact at rigidly rotated rest states and always PSD).
#include <mbi/sim/error.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace mbi::sim {

/// Isotropic linear material.
struct Material {
  double youngs_modulus = 1e5;  ///< E, Pa, > 0
  double poisson_ratio = 0.45;  ///< nu, in (-1, 0.5)
  double density = 1000.0;      ///< rho, kg/m^3, > 0
};

/// Lame parameters (Pa) of a material.
struct Lame {
  double mu = 0.0;
  double lambda = 0.0;
};

/// Validates E > 0, -1 < nu < 0.5, density > 0 (all finite) and returns mu, lambda.
/// Throws Error naming `what` (for example "element 12") and the bad field.
Lame lame(const Material& material, const char* what = "material");

// ---------------------------------------------------------------- energy density (3x3 F)

/// Proper rotation of the polar decomposition F = R S (det R = +1 for every F, also inverted
/// or flat F; S may then have one negative eigenvalue).
Eigen::Matrix3d rotation(const Eigen::Matrix3d& F);

// The inline kernels below (energy density, stress, element forces, warped element stiffness
// and its product with a vector) are the only implementation of the model: the mesh functions
// in corotational.cpp and the Simulator's assembly both call them. Fixed size, no allocation.

/// Energy density psi(F) (J/m^3) given R = rotation(F).
inline double corotational_psi(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R,
                               const Lame& lame) {
  // ||S - I||^2 = ||F - R||^2 for F = R S.
  const double tr = (R.transpose() * F).trace() - 3.0;
  return lame.mu * (F - R).squaredNorm() + 0.5 * lame.lambda * tr * tr;
}

/// First Piola-Kirchhoff stress dpsi/dF (Pa) given R = rotation(F).
inline Eigen::Matrix3d corotational_stress(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R,
                                           const Lame& lame) {
  const double tr = (R.transpose() * F).trace() - 3.0;
  Eigen::Matrix3d P = 2.0 * lame.mu * (F - R);
  P += lame.lambda * tr * R;
  return P;
}

// ---------------------------------------------------------------- one element

/// Rest data of one tetrahedron with rest corners u0..u3 (columns of Urest, 3 x 4).
struct TetRest {
  Eigen::Matrix3d Dm_inv;              ///< inverse of [u1-u0, u2-u0, u3-u0]
  Eigen::Matrix<double, 3, 4> grad;    ///< shape-function gradients g_a (1/m), sum_a g_a = 0
  double volume = 0.0;                 ///< |volume| > 0, m^3
};

/// Throws Error (naming `element`) if the tetrahedron is degenerate:
/// |volume| <= 1e-12 * (mean edge length)^3, or non-finite corners.
TetRest tet_rest(const Eigen::Matrix<double, 3, 4>& Urest, int element = -1);

/// Deformation gradient F = Ds Dm^-1 of corners x0..x3 (columns of Xdef).
Eigen::Matrix3d deformation_gradient(const TetRest& rest, const Eigen::Matrix<double, 3, 4>& Xdef);

// Element kernels take the shape-function gradients G = TetRest::grad (3 x 4, 1/m) and the rest
// volume V (m^3) directly, so that callers may store them in their own layout.

/// Corner forces (N) of stress P (Pa): column a is f_a = -V P g_a (minus dE_e/dx_a).
inline Eigen::Matrix<double, 3, 4> tet_forces(const Eigen::Matrix<double, 3, 4>& G, double V,
                                              const Eigen::Matrix3d& P) {
  Eigen::Matrix<double, 3, 4> f;
  f.noalias() = P * G;
  f *= -V;
  return f;
}

/// Adds block (a, b) of scale * R K R^T / V (3 x 3) to B, where RG = R G: with scale = V that
/// is block (a, b) of warped_tet_stiffness (N/m), K_ab below. Accumulates in place because the
/// simulator sums it into its global blocks (measured: returning it by value cost ~8% of the
/// assembly time).
inline void add_warped_tet_block(const Eigen::Matrix<double, 3, 4>& G,
                                 const Eigen::Matrix<double, 3, 4>& RG, const Lame& lame,
                                 double scale, int a, int b, Eigen::Matrix3d& B) {
  B.noalias() += (scale * lame.lambda) * RG.col(a) * RG.col(b).transpose();
  B.noalias() += (scale * lame.mu) * RG.col(b) * RG.col(a).transpose();
  B.diagonal().array() += scale * lame.mu * G.col(a).dot(G.col(b));
}

/// Warped element stiffness R K R^T, 12 x 12, N/m (rows 3a..3a+2: corner a).
inline Eigen::Matrix<double, 12, 12> warped_tet_stiffness(const TetRest& rest, const Lame& lame,
                                                          const Eigen::Matrix3d& R) {
  Eigen::Matrix<double, 3, 4> RG;
  RG.noalias() = R * rest.grad;
  Eigen::Matrix<double, 12, 12> K;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      Eigen::Matrix3d B = Eigen::Matrix3d::Zero();
      add_warped_tet_block(rest.grad, RG, lame, rest.volume, a, b, B);
      K.block<3, 3>(3 * a, 3 * b) = B;
    }
  return K;
}

/// R K R^T applied to corner vectors v (3 x 4, column a = corner a), without forming the matrix:
/// V R sigma(R^T v G^T) G with sigma(A) = mu (A + A^T) + lambda tr(A) I. Units: N/m times v's.
inline Eigen::Matrix<double, 3, 4> warped_tet_product(const Eigen::Matrix<double, 3, 4>& G,
                                                      double V, const Lame& lame,
                                                      const Eigen::Matrix3d& R,
                                                      const Eigen::Matrix<double, 3, 4>& v) {
  Eigen::Matrix3d A;  // rest-frame gradient of v
  A.noalias() = R.transpose() * v * G.transpose();
  Eigen::Matrix3d sigma = lame.mu * (A + A.transpose());
  sigma.diagonal().array() += lame.lambda * A.trace();
  Eigen::Matrix<double, 3, 4> out;
  out.noalias() = R * sigma * G;
  out *= V;
  return out;
}

/// Rest (linear) element stiffness K, 12 x 12, N/m; block (a, b) couples corners a and b:
///   K_ab = V (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a . g_b) I).
inline Eigen::Matrix<double, 12, 12> linear_tet_stiffness(const TetRest& rest, const Lame& lame) {
  return warped_tet_stiffness(rest, lame, Eigen::Matrix3d::Identity());
}

// ---------------------------------------------------------------- assembled mesh

/// Per-element Lame parameters and rest data for a mesh; validates everything (throws Error
/// naming the element / node / argument). per_element: empty, or m materials overriding `base`.
struct MeshRest {
  std::vector<TetRest> tets;
  std::vector<Lame> lame;
  std::vector<double> density;
};
MeshRest mesh_rest(const Eigen::Ref<const Eigen::MatrixXd>& U,
                   const Eigen::Ref<const Eigen::MatrixXi>& T, const Material& base,
                   const std::vector<Material>& per_element = {});

/// Co-rotational elastic energy (J) of the deformed positions X (n x 3).
double elastic_energy(const MeshRest& rest, const Eigen::Ref<const Eigen::MatrixXi>& T,
                      const Eigen::Ref<const Eigen::MatrixXd>& X);

/// Elastic node forces (N), n x 3: minus the gradient of elastic_energy.
Eigen::MatrixXd elastic_forces(const MeshRest& rest, const Eigen::Ref<const Eigen::MatrixXi>& T,
                               const Eigen::Ref<const Eigen::MatrixXd>& X);

/// Warped stiffness sum_e R_e K_e R_e^T (3n x 3n, N/m), R_e = rotation of element e in X.
Eigen::SparseMatrix<double> warped_stiffness(const MeshRest& rest,
                                             const Eigen::Ref<const Eigen::MatrixXi>& T,
                                             const Eigen::Ref<const Eigen::MatrixXd>& X);

/// Exact Hessian of elastic_energy at X (3n x 3n, N/m), including the derivative of R. May be
/// indefinite. Where two singular values of F sum to ~0 (an element flattened through an edge)
/// the derivative of R is undefined; that element's term then falls back to the warped one.
Eigen::SparseMatrix<double> corotational_hessian(const MeshRest& rest,
                                                 const Eigen::Ref<const Eigen::MatrixXi>& T,
                                                 const Eigen::Ref<const Eigen::MatrixXd>& X);

/// Plain linear-elasticity stiffness sum_e K_e (3n x 3n, N/m, n = nodes): the small-strain
/// baseline.
Eigen::SparseMatrix<double> linear_stiffness(const MeshRest& rest,
                                             const Eigen::Ref<const Eigen::MatrixXi>& T,
                                             int nodes);

/// Lumped masses (kg), n: each element gives rho V / 4 to each corner.
Eigen::VectorXd lumped_masses(const MeshRest& rest, const Eigen::Ref<const Eigen::MatrixXi>& T,
                              int nodes);

}  // namespace mbi::sim
