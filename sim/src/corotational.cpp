#include <mbi/sim/corotational.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>

namespace mbi::sim {
namespace {

bool finite(double x) { return std::isfinite(x); }

Eigen::Vector3d axial(const Eigen::Matrix3d& A) {  // A skew: A = [a]x
  return Eigen::Vector3d(A(2, 1), A(0, 2), A(1, 0));
}

Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  W << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return W;
}

Eigen::Matrix<double, 3, 4> corners(const Eigen::Ref<const Eigen::MatrixXd>& X,
                                    const Eigen::Ref<const Eigen::MatrixXi>& T, int e) {
  Eigen::Matrix<double, 3, 4> C;
  for (int a = 0; a < 4; ++a) C.col(a) = X.row(T(e, a)).transpose();
  return C;
}

void check_deformed(const MeshRest& rest, const Eigen::Ref<const Eigen::MatrixXi>& T,
                    const Eigen::Ref<const Eigen::MatrixXd>& X) {
  if (static_cast<size_t>(T.rows()) != rest.tets.size() || T.cols() != 4)
    throw Error("T must be m x 4 with the m elements of MeshRest");
  if (X.cols() != 3) throw Error("X must be n x 3");
  for (Eigen::Index e = 0; e < T.rows(); ++e)
    for (int a = 0; a < 4; ++a)
      if (T(e, a) < 0 || T(e, a) >= X.rows())
        throw Error("element " + std::to_string(e) + " has node index " +
                    std::to_string(T(e, a)) + " outside X's " + std::to_string(X.rows()) +
                    " rows");
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    if (!X.row(i).allFinite())
      throw Error("X has a non-finite position at node " + std::to_string(i));
}

/// Element Hessian contributions: H_ab(k, l) = V (dP(e_l g_b^T) g_a)_k.
template <typename DP>
Eigen::Matrix<double, 12, 12> element_matrix(const TetRest& r, DP&& dP) {
  Eigen::Matrix<double, 12, 12> H;
  for (int b = 0; b < 4; ++b)
    for (int l = 0; l < 3; ++l) {
      Eigen::Matrix3d dF = Eigen::Matrix3d::Zero();
      dF.row(l) = r.grad.col(b).transpose();
      const Eigen::Matrix3d D = dP(dF);
      for (int a = 0; a < 4; ++a) H.block<3, 1>(3 * a, 3 * b + l) = r.volume * (D * r.grad.col(a));
    }
  return H;
}

Eigen::SparseMatrix<double> assemble(const Eigen::Ref<const Eigen::MatrixXi>& T, int n,
                                     const std::vector<Eigen::Matrix<double, 12, 12>>& Ke) {
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(Ke.size() * 144);
  for (size_t e = 0; e < Ke.size(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int k = 0; k < 3; ++k)
          for (int l = 0; l < 3; ++l)
            trip.emplace_back(3 * T(e, a) + k, 3 * T(e, b) + l, Ke[e](3 * a + k, 3 * b + l));
  Eigen::SparseMatrix<double> K(3 * n, 3 * n);
  K.setFromTriplets(trip.begin(), trip.end());
  return K;
}

}  // namespace

Lame lame(const Material& m, const char* what) {
  const std::string w = what ? what : "material";
  if (!finite(m.youngs_modulus) || m.youngs_modulus <= 0)
    throw Error("" + w + ": Young's modulus must be finite and > 0 Pa, got " +
                std::to_string(m.youngs_modulus));
  if (!finite(m.poisson_ratio) || m.poisson_ratio <= -1.0 || m.poisson_ratio >= 0.5)
    throw Error("" + w + ": Poisson ratio must lie in (-1, 0.5), got " +
                std::to_string(m.poisson_ratio));
  if (!finite(m.density) || m.density <= 0)
    throw Error("" + w + ": density must be finite and > 0 kg/m^3, got " +
                std::to_string(m.density));
  const double E = m.youngs_modulus, nu = m.poisson_ratio;
  return {E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))};
}

namespace {

Eigen::Matrix3d rotation_svd(const Eigen::Matrix3d& F) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  // Singular values are sorted decreasingly: flip the smallest one's vector if needed.
  if (U.determinant() * V.determinant() < 0) U.col(2) = -U.col(2);
  Eigen::Matrix3d R;
  R.noalias() = U * V.transpose();
  return R;
}

}  // namespace

Eigen::Matrix3d rotation(const Eigen::Matrix3d& F) {
  // Fast path: eigen-decomposition of F^T F (closed form) gives V and the singular values;
  // U follows from F V by Gram-Schmidt, its last column as a cross product so that det U = +1
  // (which flips the smallest singular value of an inverted F, as in Irving et al. 2004).
  const double scale = F.cwiseAbs().maxCoeff();
  if (!(scale > 0) || !std::isfinite(scale)) return Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d Fs = F / scale;
  Eigen::Matrix3d C;
  C.noalias() = Fs.transpose() * Fs;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(C);
  Eigen::Matrix3d V = eig.eigenvectors();  // ascending eigenvalues: column 2 is the largest
  const Eigen::Vector3d lam = eig.eigenvalues();
  // Near-repeated small singular values or a rank <= 1 F: the closed form loses accuracy.
  if (!(lam(1) > 1e-8 * lam(2)) || !V.allFinite()) return rotation_svd(F);
  if (V.determinant() < 0) V.col(0) = -V.col(0);
  Eigen::Vector3d u2 = Fs * V.col(2);
  u2.normalize();
  Eigen::Vector3d u1 = Fs * V.col(1);
  u1 -= u1.dot(u2) * u2;
  const double n1 = u1.norm();
  if (!(n1 > 1e-6 * std::sqrt(lam(2)))) return rotation_svd(F);
  u1 /= n1;
  Eigen::Matrix3d U;
  U.col(2) = u2;
  U.col(1) = u1;
  U.col(0) = u1.cross(u2);
  Eigen::Matrix3d R;
  R.noalias() = U * V.transpose();
  return R;
}

TetRest tet_rest(const Eigen::Matrix<double, 3, 4>& C, int element) {
  const std::string who =
      element >= 0 ? "element " + std::to_string(element) : std::string("tetrahedron");
  if (!C.allFinite()) throw Error("" + who + " has a non-finite corner");
  Eigen::Matrix3d Dm;
  for (int a = 0; a < 3; ++a) Dm.col(a) = C.col(a + 1) - C.col(0);
  double edge = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) edge += (C.col(a) - C.col(b)).norm();
  edge /= 6.0;
  const double det = Dm.determinant();
  if (!(std::abs(det) / 6.0 > 1e-12 * edge * edge * edge))
    throw Error("" + who + " is degenerate (volume " + std::to_string(det / 6.0) +
                " m^3, mean edge " + std::to_string(edge) + " m)");
  TetRest r;
  r.Dm_inv = Dm.inverse();
  r.volume = std::abs(det) / 6.0;
  // F = sum_a x_a g_a^T with g_{1..3} = rows of Dm^-1, g_0 = -sum.
  r.grad.rightCols<3>() = r.Dm_inv.transpose();
  r.grad.col(0) = -r.grad.rightCols<3>().rowwise().sum();
  return r;
}

Eigen::Matrix3d deformation_gradient(const TetRest& rest, const Eigen::Matrix<double, 3, 4>& X) {
  Eigen::Matrix3d F;
  F.noalias() = X * rest.grad.transpose();
  return F;
}

MeshRest mesh_rest(const Eigen::Ref<const Eigen::MatrixXd>& U,
                   const Eigen::Ref<const Eigen::MatrixXi>& T, const Material& base,
                   const std::vector<Material>& per_element) {
  if (U.cols() != 3) throw Error("rest positions U must be n x 3, got n x " +
                                 std::to_string(U.cols()));
  if (T.cols() != 4) throw Error("elements T must be m x 4, got m x " +
                                 std::to_string(T.cols()));
  if (T.rows() == 0) throw Error("the mesh has no elements");
  if (!per_element.empty() && per_element.size() != static_cast<size_t>(T.rows()))
    throw Error("per_element materials: expected " + std::to_string(T.rows()) +
                " (one per element) or none, got " + std::to_string(per_element.size()));
  for (Eigen::Index i = 0; i < U.rows(); ++i)
    if (!U.row(i).allFinite())
      throw Error("rest position of node " + std::to_string(i) + " is not finite");
  MeshRest r;
  r.tets.reserve(T.rows());
  r.lame.reserve(T.rows());
  r.density.reserve(T.rows());
  const Lame base_lame = lame(base, "material");
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    for (int a = 0; a < 4; ++a) {
      if (T(e, a) < 0 || T(e, a) >= U.rows())
        throw Error("element " + std::to_string(e) + " has node index " +
                    std::to_string(T(e, a)) + " outside [0, " + std::to_string(U.rows()) + ")");
      for (int b = 0; b < a; ++b)
        if (T(e, a) == T(e, b))
          throw Error("element " + std::to_string(e) + " repeats node " +
                      std::to_string(T(e, a)));
    }
    r.tets.push_back(tet_rest(corners(U, T, static_cast<int>(e)), static_cast<int>(e)));
    if (per_element.empty()) {
      r.lame.push_back(base_lame);
      r.density.push_back(base.density);
    } else {
      const std::string who = "element " + std::to_string(e);
      r.lame.push_back(lame(per_element[e], who.c_str()));
      r.density.push_back(per_element[e].density);
    }
  }
  return r;
}

double elastic_energy(const MeshRest& rest, const Eigen::Ref<const Eigen::MatrixXi>& T,
                      const Eigen::Ref<const Eigen::MatrixXd>& X) {
  check_deformed(rest, T, X);
  double E = 0.0;
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    const TetRest& r = rest.tets[e];
    const Eigen::Matrix3d F = deformation_gradient(r, corners(X, T, static_cast<int>(e)));
    E += r.volume * corotational_psi(F, rotation(F), rest.lame[e]);
  }
  return E;
}

Eigen::MatrixXd elastic_forces(const MeshRest& rest, const Eigen::Ref<const Eigen::MatrixXi>& T,
                               const Eigen::Ref<const Eigen::MatrixXd>& X) {
  check_deformed(rest, T, X);
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(X.rows(), 3);
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    const TetRest& r = rest.tets[e];
    const Eigen::Matrix3d F = deformation_gradient(r, corners(X, T, static_cast<int>(e)));
    const Eigen::Matrix3d P = corotational_stress(F, rotation(F), rest.lame[e]);
    const Eigen::Matrix<double, 3, 4> fe = tet_forces(r.grad, r.volume, P);
    for (int a = 0; a < 4; ++a) f.row(T(e, a)) += fe.col(a).transpose();
  }
  return f;
}

Eigen::SparseMatrix<double> warped_stiffness(const MeshRest& rest,
                                             const Eigen::Ref<const Eigen::MatrixXi>& T,
                                             const Eigen::Ref<const Eigen::MatrixXd>& X) {
  check_deformed(rest, T, X);
  std::vector<Eigen::Matrix<double, 12, 12>> Ke(T.rows());
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    const Eigen::Matrix3d F =
        deformation_gradient(rest.tets[e], corners(X, T, static_cast<int>(e)));
    Ke[e] = warped_tet_stiffness(rest.tets[e], rest.lame[e], rotation(F));
  }
  return assemble(T, static_cast<int>(X.rows()), Ke);
}

Eigen::SparseMatrix<double> corotational_hessian(const MeshRest& rest,
                                                 const Eigen::Ref<const Eigen::MatrixXi>& T,
                                                 const Eigen::Ref<const Eigen::MatrixXd>& X) {
  check_deformed(rest, T, X);
  std::vector<Eigen::Matrix<double, 12, 12>> Ke(T.rows());
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    const TetRest& r = rest.tets[e];
    const Lame& L = rest.lame[e];
    const Eigen::Matrix3d F = deformation_gradient(r, corners(X, T, static_cast<int>(e)));
    const Eigen::Matrix3d R = rotation(F);
    Eigen::Matrix3d S;
    S.noalias() = R.transpose() * F;
    S = 0.5 * (S + S.transpose()).eval();
    // dR = R [w]x with (tr(S) I - S) w = axial(R^T dF - dF^T R); its eigenvalues are the
    // pairwise sums of the (signed) singular values.
    Eigen::Matrix3d G = S.trace() * Eigen::Matrix3d::Identity() - S;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(G, Eigen::EigenvaluesOnly);
    const double scale = std::max(1.0, S.cwiseAbs().maxCoeff());
    if (eig.eigenvalues().cwiseAbs().minCoeff() <= 1e-8 * scale) {
      Ke[e] = warped_tet_stiffness(r, L, R);
      continue;
    }
    const Eigen::Matrix3d Ginv = G.inverse();
    const double trS = S.trace() - 3.0;
    Ke[e] = element_matrix(r, [&](const Eigen::Matrix3d& dF) {
      Eigen::Matrix3d A;
      A.noalias() = R.transpose() * dF;
      const Eigen::Matrix3d Ask = A - A.transpose();
      Eigen::Vector3d w;
      w.noalias() = Ginv * axial(Ask);
      Eigen::Matrix3d dR;
      dR.noalias() = R * cross_matrix(w);
      Eigen::Matrix3d dP = 2.0 * L.mu * dF;
      dP += L.lambda * A.trace() * R;
      dP += (L.lambda * trS - 2.0 * L.mu) * dR;
      return dP;
    });
  }
  return assemble(T, static_cast<int>(X.rows()), Ke);
}

Eigen::SparseMatrix<double> linear_stiffness(const MeshRest& rest,
                                             const Eigen::Ref<const Eigen::MatrixXi>& T,
                                             int n) {
  check_deformed(rest, T, Eigen::MatrixXd::Zero(n, 3));
  std::vector<Eigen::Matrix<double, 12, 12>> Ke(T.rows());
  for (Eigen::Index e = 0; e < T.rows(); ++e) Ke[e] = linear_tet_stiffness(rest.tets[e], rest.lame[e]);
  return assemble(T, n, Ke);
}

Eigen::VectorXd lumped_masses(const MeshRest& rest, const Eigen::Ref<const Eigen::MatrixXi>& T,
                              int nodes) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(nodes);
  for (Eigen::Index e = 0; e < T.rows(); ++e)
    for (int a = 0; a < 4; ++a) {
      if (T(e, a) < 0 || T(e, a) >= nodes)
        throw Error("element " + std::to_string(e) + " has node index " +
                    std::to_string(T(e, a)) + " outside [0, " + std::to_string(nodes) + ")");
      m(T(e, a)) += 0.25 * rest.density[e] * rest.tets[e].volume;
    }
  return m;
}

}  // namespace mbi::sim
