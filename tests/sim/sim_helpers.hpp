#pragma once
// Shared set-ups for the simulator tests.
#include <common/grid_meshes.hpp>
#include <mbi/sim/simulator.hpp>

#include <Eigen/SparseCholesky>
#include <vector>

namespace mbi::test {

/// Nodes with |U(i, axis) - value| <= tol.
inline std::vector<int> nodes_at(const Eigen::MatrixXd& U, int axis, double value,
                                 double tol = 1e-9) {
  std::vector<int> out;
  for (Eigen::Index i = 0; i < U.rows(); ++i)
    if (std::abs(U(i, axis) - value) <= tol) out.push_back(static_cast<int>(i));
  return out;
}

/// Bar along x: length L, square cross-section h x h, (nx, ny, nz) cells.
inline Mesh bar(int nx, int ny, int nz, double L, double h) {
  return box_tet_mesh(nx, ny, nz, Eigen::Vector3d(L, h, h));
}

/// Mean y displacement of the nodes at x = L.
inline double tip_deflection(const Eigen::MatrixXd& U, const Eigen::MatrixXd& X, double L) {
  const auto tip = nodes_at(U, 0, L, 1e-9 * L);
  double s = 0.0;
  for (int i : tip) s += X(i, 1) - U(i, 1);
  return s / static_cast<double>(tip.size());
}

/// Plain linear FEM static solution (test-only baseline): K u = f with the `fixed` nodes
/// displaced to `fixed_pos` (rows in the order of `fixed`). Returns deformed positions.
inline Eigen::MatrixXd linear_static(const Mesh& M, const sim::Material& mat,
                                     const Eigen::Vector3d& gravity, const std::vector<int>& fixed,
                                     const Eigen::MatrixXd& fixed_pos) {
  const int n = static_cast<int>(M.U.rows());
  const sim::MeshRest rest = sim::mesh_rest(M.U, M.T, mat);
  const Eigen::SparseMatrix<double> K = sim::linear_stiffness(rest, M.T, n);
  const Eigen::VectorXd m = sim::lumped_masses(rest, M.T, n);
  std::vector<int> map(3 * n, -1);
  std::vector<char> is_fixed(n, 0);
  for (int i : fixed) is_fixed[i] = 1;
  int nf = 0;
  for (int i = 0; i < n; ++i)
    if (!is_fixed[i])
      for (int c = 0; c < 3; ++c) map[3 * i + c] = nf++;
  Eigen::VectorXd uc = Eigen::VectorXd::Zero(3 * n);
  for (size_t j = 0; j < fixed.size(); ++j)
    uc.segment<3>(3 * fixed[j]) = (fixed_pos.row(j) - M.U.row(fixed[j])).transpose();
  Eigen::VectorXd f(3 * n);
  for (int i = 0; i < n; ++i) f.segment<3>(3 * i) = m(i) * gravity;
  const Eigen::VectorXd Kuc = K * uc;
  std::vector<Eigen::Triplet<double>> trip;
  for (int k = 0; k < K.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, k); it; ++it)
      if (map[it.row()] >= 0 && map[it.col()] >= 0)
        trip.emplace_back(map[it.row()], map[it.col()], it.value());
  Eigen::SparseMatrix<double> Kff(nf, nf);
  Kff.setFromTriplets(trip.begin(), trip.end());
  Eigen::VectorXd rhs(nf);
  for (int d = 0; d < 3 * n; ++d)
    if (map[d] >= 0) rhs(map[d]) = f(d) - Kuc(d);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(Kff);
  const Eigen::VectorXd uf = ldlt.solve(rhs);
  Eigen::MatrixXd X = M.U;
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      X(i, c) += map[3 * i + c] >= 0 ? uf(map[3 * i + c]) : uc(3 * i + c);
  return X;
}

/// E = sum_i k m_i / 2 |x_i - target_i|^2: mass-proportional springs, so pulling every node
/// toward a rigid copy of the mesh has a rigid minimiser.
struct MassSprings : sim::Potential {
  Eigen::VectorXd k_dof, target;
  double energy(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return 0.5 * (x - target).dot(k_dof.cwiseProduct(x - target));
  }
  void add_gradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                    Eigen::Ref<Eigen::VectorXd> g) const override {
    g += k_dof.cwiseProduct(x - target);
  }
  void hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>&,
                      std::vector<sim::NodeBlock>& out) const override {
    for (Eigen::Index i = 0; i < k_dof.size() / 3; ++i)
      out.push_back({int(i), int(i), k_dof(3 * i) * Eigen::Matrix3d::Identity()});
  }
};

/// MassSprings whose blocks are a fraction of its Hessian (a tenth by default), with (product) or
/// without the exact Hessian product.
struct WeakSprings : MassSprings {
  double fraction = 0.1;
  bool product = true;
  void hessian_blocks(const Eigen::Ref<const Eigen::VectorXd>&, std::vector<sim::NodeBlock>& out) const override {
    for (Eigen::Index i = 0; i < k_dof.size() / 3; ++i)
      out.push_back({int(i), int(i), fraction * k_dof(3 * i) * Eigen::Matrix3d::Identity()});
  }
  bool add_hessian_product(const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>& v,
                           Eigen::Ref<Eigen::VectorXd> out) const override {
    if (product) out += k_dof.cwiseProduct(v);
    return product;
  }
};

}  // namespace mbi::test
