// Harmonic extension: P1 stiffness assembled once, its free block factored, one solve a call.
#include <mbi/interp/harmonic.hpp>
#include <mbi/interp/mesh.hpp>

#include "linalg/factor.hpp"

#include <Eigen/SparseCore>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

namespace mbi::interp {

namespace {

using SpMat = Eigen::SparseMatrix<double>;

// place[v]: -1 for a fixed node, -2 for a node no element uses, else its index among the free ones.
std::vector<int> free_places(int n, const Eigen::Ref<const Eigen::MatrixXi>& T, const Eigen::Ref<const Eigen::VectorXi>& fixed) {
  std::vector<int> place(n, -2);
  for (Eigen::Index e = 0; e < T.rows(); ++e)
    for (Eigen::Index k = 0; k < T.cols(); ++k) place[T(e, k)] = 0;
  for (Eigen::Index i = 0; i < fixed.size(); ++i) {
    const int v = fixed[i];
    if (v < 0 || v >= n)
      throw Error("fixed: index " + std::to_string(v) + " at position " + std::to_string(i) + " is not a node (0.." +
                  std::to_string(n - 1) + ")");
    if (place[v] == -1) throw Error("fixed: node " + std::to_string(v) + " is given twice");
    place[v] = -1;
  }
  int next = 0;
  for (int& p : place)
    if (p == 0) p = next++;
  return place;
}

// Union of each element's nodes; throws naming a free node whose part of the mesh has no fixed node.
void check_connected(const Eigen::Ref<const Eigen::MatrixXi>& T, const std::vector<int>& place) {
  std::vector<int> root(place.size());
  std::iota(root.begin(), root.end(), 0);
  auto find = [&](int v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  for (Eigen::Index e = 0; e < T.rows(); ++e)
    for (Eigen::Index k = 1; k < T.cols(); ++k) root[find(T(e, k))] = find(T(e, 0));
  std::vector<char> anchored(place.size(), 0);
  for (size_t v = 0; v < place.size(); ++v)
    if (place[v] == -1) anchored[find(static_cast<int>(v))] = 1;
  for (size_t v = 0; v < place.size(); ++v)
    if (place[v] >= 0 && !anchored[find(static_cast<int>(v))])
      throw Error("node " + std::to_string(v) + " is free but its part of the mesh has no fixed node: "
                  "its position would be undetermined");
}

}  // namespace

struct HarmonicExtension::Impl {
  Eigen::MatrixXd U_free;  // free nodes' rest positions
  Eigen::MatrixXd U_fixed;
  Eigen::VectorXi free, fixed;
  Eigen::SparseMatrix<double, Eigen::RowMajor> K_IB;  // coupling of free rows to fixed columns
  detail::CholeskyFactor K_II;
};

HarmonicExtension::HarmonicExtension(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                     const Eigen::Ref<const Eigen::MatrixXi>& T,
                                     const Eigen::Ref<const Eigen::VectorXi>& fixed)
    : impl_(std::make_unique<Impl>()) {
  validate_mesh(U, T);
  const int n = static_cast<int>(U.rows()), d = static_cast<int>(U.cols());
  const std::vector<int> place = free_places(n, T, fixed);
  check_connected(T, place);
  Impl& I = *impl_;
  std::vector<int> fixed_place(n, -1);
  int nf = 0, nb = 0;
  for (int v = 0; v < n; ++v) nf += place[v] >= 0;
  I.free.resize(nf);
  I.fixed.resize(fixed.size());
  for (int v = 0, a = 0; v < n; ++v) {
    if (place[v] >= 0) I.free[a++] = v;
    if (place[v] == -1) I.fixed[fixed_place[v] = nb++] = v;
  }
  std::vector<Eigen::Triplet<double>> ii, ib;
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    const Eigen::MatrixXd G = basis_gradients(U, T, static_cast<int>(e));  // (d+1) x d
    const double volume = std::abs(element_volume(U, T, static_cast<int>(e)));
    const Eigen::MatrixXd local = volume * (G * G.transpose());
    for (int a = 0; a <= d; ++a) {
      const int row = place[T(e, a)];
      if (row < 0) continue;
      for (int b = 0; b <= d; ++b) {
        const int v = T(e, b);
        if (place[v] >= 0) ii.emplace_back(row, place[v], local(a, b));
        else ib.emplace_back(row, fixed_place[v], local(a, b));
      }
    }
  }
  SpMat A(nf, nf);
  A.setFromTriplets(ii.begin(), ii.end());
  I.K_IB.resize(nf, nb);
  I.K_IB.setFromTriplets(ib.begin(), ib.end());
  if (nf > 0) I.K_II = detail::cholesky(A, detail::cholmod_available());
  I.U_free.resize(nf, d);
  for (int a = 0; a < nf; ++a) I.U_free.row(a) = U.row(I.free[a]);
  I.U_fixed.resize(nb, d);
  for (int b = 0; b < nb; ++b) I.U_fixed.row(b) = U.row(I.fixed[b]);
}

HarmonicExtension::HarmonicExtension(HarmonicExtension&&) noexcept = default;
HarmonicExtension& HarmonicExtension::operator=(HarmonicExtension&&) noexcept = default;
HarmonicExtension::~HarmonicExtension() = default;

void HarmonicExtension::apply(Eigen::Ref<Eigen::MatrixXd> X) const {
  const Impl& I = *impl_;
  const Eigen::Index n = I.free.size() + I.fixed.size(), d = I.U_free.cols();
  if (X.cols() != d || X.rows() < n)
    throw Error("X must be (n, " + std::to_string(d) + ") with the mesh's nodes, got (" + std::to_string(X.rows()) +
                ", " + std::to_string(X.cols()) + ")");
  if (I.free.size() == 0) return;
  Eigen::MatrixXd moved(I.fixed.size(), d);
  for (Eigen::Index b = 0; b < I.fixed.size(); ++b) moved.row(b) = X.row(I.fixed[b]) - I.U_fixed.row(b);
  // row-major right-hand sides, as the factor's sweeps take them: -K_IB (X_B - U_B)
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> y = -(I.K_IB * moved);
  I.K_II.solve(y.data(), static_cast<int>(d));
  for (Eigen::Index a = 0; a < I.free.size(); ++a) X.row(I.free[a]) = I.U_free.row(a) + y.row(a);
}

const Eigen::VectorXi& HarmonicExtension::free_nodes() const { return impl_->free; }
const Eigen::VectorXi& HarmonicExtension::fixed_nodes() const { return impl_->fixed; }

long long HarmonicExtension::memory_bytes() const {
  const Impl& I = *impl_;
  return static_cast<long long>(I.K_II.bytes()) + I.K_IB.nonZeros() * 12LL + I.K_IB.rows() * 4LL +
         (I.U_free.size() + I.U_fixed.size()) * 8LL + (I.free.size() + I.fixed.size()) * 4LL;
}

}  // namespace mbi::interp
