// HarmonicExtension: against a dense solve of the Dirichlet system, its invariants, its errors.
#include <mbi/interp/harmonic.hpp>
#include <mbi/interp/mesh.hpp>

#include <catch2/catch.hpp>

#include "common/grid_meshes.hpp"

#include <Eigen/Dense>
#include <random>

using namespace mbi::interp;
using mbi::test::box_tet_mesh;
using mbi::test::square_tri_mesh;

namespace {

Eigen::VectorXi boundary_of(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T) {
  const Eigen::VectorXi on = boundary_vertices(static_cast<int>(U.rows()), T);
  Eigen::VectorXi nodes(on.sum());
  for (Eigen::Index v = 0, k = 0; v < on.size(); ++v)
    if (on[v]) nodes[k++] = static_cast<int>(v);
  return nodes;
}

// The free nodes' positions from the full dense stiffness K on the displacements D = X - U:
// K_II D_I = -K_IB D_B, assembled here from the element gradients without the class's code.
Eigen::MatrixXd dense_extension(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T, const Eigen::VectorXi& fixed,
                                const Eigen::MatrixXd& X) {
  const Eigen::Index n = U.rows(), d = U.cols();
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
  for (int e = 0; e < T.rows(); ++e) {
    const Eigen::MatrixXd G = basis_gradients(U, T, e);
    const Eigen::MatrixXd local = std::abs(element_volume(U, T, e)) * G * G.transpose();
    for (int a = 0; a <= d; ++a)
      for (int b = 0; b <= d; ++b) K(T(e, a), T(e, b)) += local(a, b);
  }
  std::vector<int> is_fixed(n, 0), free;
  for (Eigen::Index i = 0; i < fixed.size(); ++i) is_fixed[fixed[i]] = 1;
  for (int v = 0; v < n; ++v)
    if (!is_fixed[v]) free.push_back(v);
  Eigen::MatrixXd A(free.size(), free.size()), rhs = Eigen::MatrixXd::Zero(free.size(), d);
  for (size_t a = 0; a < free.size(); ++a) {
    for (size_t b = 0; b < free.size(); ++b) A(a, b) = K(free[a], free[b]);
    for (Eigen::Index i = 0; i < fixed.size(); ++i)
      rhs.row(a) -= K(free[a], fixed[i]) * (X.row(fixed[i]) - U.row(fixed[i]));
  }
  const Eigen::MatrixXd D = A.ldlt().solve(rhs);
  Eigen::MatrixXd out = X;
  for (size_t a = 0; a < free.size(); ++a) out.row(free[a]) = U.row(free[a]) + D.row(a);
  return out;
}

Eigen::MatrixXd jittered(Eigen::MatrixXd U, double amount, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amount, amount);
  for (Eigen::Index i = 0; i < U.size(); ++i) U.data()[i] += u(rng);
  return U;
}

}  // namespace

TEST_CASE("harmonic extension: equals a dense solve of the Dirichlet system, 3D and 2D", "[harmonic]") {
  for (int d : {3, 2}) {
    const auto M = d == 3 ? box_tet_mesh(4, 3, 3) : square_tri_mesh(6, 5);
    const Eigen::MatrixXd U = jittered(M.U, 0.03, 7);  // interior nodes off the grid: uneven weights
    const Eigen::VectorXi fixed = boundary_of(U, M.T);
    const HarmonicExtension h(U, M.T, fixed);
    CHECK(h.free_nodes().size() + h.fixed_nodes().size() == U.rows());
    REQUIRE(h.free_nodes().size() > 0);
    Eigen::MatrixXd X = jittered(U, 0.2, 11);  // every node moved; only the fixed rows may count
    const Eigen::MatrixXd expected = dense_extension(U, M.T, fixed, X);
    h.apply(X);
    CHECK((X - expected).cwiseAbs().maxCoeff() < 1e-12);
  }
}

TEST_CASE("harmonic extension: identity at rest, affine motions kept", "[harmonic]") {
  const auto M = box_tet_mesh(3, 3, 4);
  const Eigen::MatrixXd U = jittered(M.U, 0.02, 3);
  const HarmonicExtension h(U, M.T, boundary_of(U, M.T));
  Eigen::MatrixXd X = U;
  h.apply(X);
  CHECK(X == U);
  Eigen::Matrix3d A;
  A << 1.2, 0.3, -0.1, 0.0, 0.8, 0.2, 0.1, -0.2, 1.1;
  const Eigen::MatrixXd affine = (U * A.transpose()).rowwise() + Eigen::RowVector3d(0.5, -1, 2);
  Eigen::MatrixXd Y = affine;
  Y(h.free_nodes()[0], 0) += 100;  // a free row's input is ignored
  h.apply(Y);
  CHECK((Y - affine).cwiseAbs().maxCoeff() < 1e-12);
}

TEST_CASE("harmonic extension: any fixed set, nodes no element uses left as given", "[harmonic]") {
  auto M = box_tet_mesh(3, 3, 3);
  Eigen::MatrixXd U(M.U.rows() + 1, 3);
  U << M.U, Eigen::RowVector3d(5, 5, 5);  // a loose node
  Eigen::VectorXi fixed(3);
  fixed << 0, 13, 63;  // a corner, an interior node, the far corner
  const HarmonicExtension h(U, M.T, fixed);
  CHECK(h.free_nodes().size() == M.U.rows() - 3);
  Eigen::MatrixXd X = jittered(U, 0.1, 5);
  const Eigen::RowVector3d loose = X.row(U.rows() - 1);
  Eigen::MatrixXd expected = dense_extension(M.U, M.T, fixed, X.topRows(M.U.rows()));
  h.apply(X);
  CHECK((X.topRows(M.U.rows()) - expected).cwiseAbs().maxCoeff() < 1e-11);
  CHECK(X.row(U.rows() - 1) == loose);
}

TEST_CASE("harmonic extension: bad fixed sets and shapes are refused by name", "[harmonic]") {
  const auto M = box_tet_mesh(2, 2, 2);
  Eigen::VectorXi out_of_range(2), twice(2);
  out_of_range << 0, 27;
  twice << 4, 4;
  CHECK_THROWS_WITH(HarmonicExtension(M.U, M.T, out_of_range), Catch::Contains("fixed: index 27"));
  CHECK_THROWS_WITH(HarmonicExtension(M.U, M.T, twice), Catch::Contains("node 4 is given twice"));
  // two separate boxes, only the first one's nodes fixed: the second's would be undetermined
  Eigen::MatrixXd U(2 * M.U.rows(), 3);
  U << M.U, M.U.rowwise() + Eigen::RowVector3d(3, 0, 0);
  Eigen::MatrixXi T(2 * M.T.rows(), 4);
  T << M.T, M.T.array() + static_cast<int>(M.U.rows());
  const Eigen::VectorXi first = boundary_of(M.U, M.T);
  CHECK_THROWS_WITH(HarmonicExtension(U, T, first), Catch::Contains("no fixed node"));
  const HarmonicExtension h(M.U, M.T, first);
  Eigen::MatrixXd narrow(M.U.rows(), 2);
  CHECK_THROWS_WITH(h.apply(narrow), Catch::Contains("X must be"));
}
