// Energy density / element / mesh levels of the co-rotational model: finite-difference checks,
// rigid-motion invariance, proper rotations, bad input.
#include <catch2/catch.hpp>
#include <common/node_vectors.hpp>
#include <common/grid_meshes.hpp>
#include <mbi/sim/corotational.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

using namespace mbi::sim;
using mbi::test::flat;
using mbi::test::unflat;

namespace {

Eigen::MatrixXd perturbed(const Eigen::MatrixXd& U, double amount, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  Eigen::MatrixXd X = U;
  for (Eigen::Index i = 0; i < X.size(); ++i) X.data()[i] += amount * uni(rng);
  return X;
}

// A small irregular mesh: 2x2x2 cells, interior node jittered, then a general deformation.
struct CorotFixture {
  mbi::test::Mesh M = [] {
    auto m = mbi::test::box_tet_mesh(2, 2, 2, Eigen::Vector3d(1.0, 0.8, 1.2));
    mbi::test::jitter(m, 0.2, 0.4, 3);
    return m;
  }();
  Material mat{2e5, 0.35, 1000.0};
  MeshRest rest = mesh_rest(M.U, M.T, mat);
};

}  // namespace

TEST_CASE("rotation() is a proper rotation, also for inverted and flat F", "[sim][corot]") {
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Matrix3d F;
    for (int i = 0; i < 9; ++i) F.data()[i] = g(rng);
    if (trial % 3 == 1) F.col(2) = 0.5 * F.col(0) - F.col(1);  // flat (rank 2)
    const Eigen::Matrix3d R = rotation(F);
    CHECK((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-12);
    CHECK(R.determinant() == Approx(1.0).margin(1e-12));
    // S = R^T F is symmetric (polar decomposition).
    const Eigen::Matrix3d S = R.transpose() * F;
    CHECK((S - S.transpose()).norm() < 1e-12 * (1.0 + F.norm()));
  }
  // A pure rotation gives itself back; a reflection gives a proper rotation with energy > 0.
  const Eigen::Matrix3d Q = mbi::test::random_rotation(3, 11);
  CHECK((rotation(Q) - Q).norm() < 1e-12);
  Eigen::Matrix3d Refl = Q;
  Refl.col(0) *= -1;
  CHECK(rotation(Refl).determinant() == Approx(1.0).margin(1e-12));
  CHECK(corotational_psi(Refl, rotation(Refl), Lame{1.0, 1.0}) > 0.5);
}

TEST_CASE("forces are minus the finite-difference gradient of the energy", "[sim][corot]") {
  CorotFixture fx;
  // States: moderate strain, large rotation + strain, and inverted elements.
  const Eigen::MatrixXd R = mbi::test::random_rotation(3, 4);
  std::vector<Eigen::MatrixXd> states;
  states.push_back(perturbed(fx.M.U, 0.05, 1));
  states.push_back(perturbed(fx.M.U, 0.05, 2) * R.transpose());
  Eigen::MatrixXd inv = perturbed(fx.M.U, 0.05, 3);
  inv.col(1) *= -0.5;  // every element inverted
  states.push_back(inv);
  for (const Eigen::MatrixXd& X : states) {
    const Eigen::MatrixXd f = elastic_forces(fx.rest, fx.M.T, X);
    const Eigen::VectorXd q = flat(X);
    const double h = 1e-6;
    double worst = 0.0;
    for (Eigen::Index d = 0; d < q.size(); ++d) {
      Eigen::VectorXd qp = q, qm = q;
      qp(d) += h;
      qm(d) -= h;
      const double fd = -(elastic_energy(fx.rest, fx.M.T, unflat(qp)) -
                          elastic_energy(fx.rest, fx.M.T, unflat(qm))) / (2 * h);
      worst = std::max(worst, std::abs(fd - f(d / 3, d % 3)));
    }
    // Central differences: O(h^2) truncation + round-off ~ 1e-16 E / h; forces are O(1e4) N.
    INFO("max |f| = " << f.cwiseAbs().maxCoeff());
    CHECK(worst < 1e-6 * f.cwiseAbs().maxCoeff());
  }
}

TEST_CASE("exact Hessian matches finite differences of the forces, warped stiffness is exact "
          "at rigidly rotated rest states",
          "[sim][corot]") {
  CorotFixture fx;
  const Eigen::MatrixXd R = mbi::test::random_rotation(3, 8);
  const Eigen::MatrixXd X = perturbed(fx.M.U, 0.05, 9) * R.transpose();
  auto fd_hessian = [&](const Eigen::MatrixXd& Y) {
    const Eigen::VectorXd q = flat(Y);
    Eigen::MatrixXd H(q.size(), q.size());
    const double h = 1e-6;
    for (Eigen::Index d = 0; d < q.size(); ++d) {
      Eigen::VectorXd qp = q, qm = q;
      qp(d) += h;
      qm(d) -= h;
      H.col(d) = -(flat(elastic_forces(fx.rest, fx.M.T, unflat(qp))) -
                   flat(elastic_forces(fx.rest, fx.M.T, unflat(qm)))) / (2 * h);
    }
    return H;
  };
  const Eigen::MatrixXd Hfd = fd_hessian(X);
  const Eigen::MatrixXd H = Eigen::MatrixXd(corotational_hessian(fx.rest, fx.M.T, X));
  CHECK((H - Hfd).norm() < 1e-6 * H.norm());
  CHECK((H - H.transpose()).norm() < 1e-12 * H.norm());
  // The warped stiffness drops dR/dx: away from rest it differs from the exact Hessian...
  const Eigen::MatrixXd Kw = Eigen::MatrixXd(warped_stiffness(fx.rest, fx.M.T, X));
  CHECK((Kw - Hfd).norm() > 1e-3 * H.norm());
  // ...but at a rigid motion of the rest shape both equal R K_lin R^T.
  const Eigen::MatrixXd Xr = (fx.M.U * R.transpose()).rowwise() + Eigen::RowVector3d(1, -2, 3);
  const Eigen::MatrixXd Hr = fd_hessian(Xr);
  const Eigen::MatrixXd Kr = Eigen::MatrixXd(warped_stiffness(fx.rest, fx.M.T, Xr));
  CHECK((Kr - Hr).norm() < 1e-6 * Kr.norm());
  const int n = static_cast<int>(fx.M.U.rows());
  const Eigen::MatrixXd Klin = Eigen::MatrixXd(linear_stiffness(fx.rest, fx.M.T, n));
  Eigen::MatrixXd Rbig = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int i = 0; i < n; ++i) Rbig.block(3 * i, 3 * i, 3, 3) = R;
  CHECK((Kr - Rbig * Klin * Rbig.transpose()).norm() < 1e-10 * Kr.norm());
  // Warped stiffness is symmetric positive semi-definite; translations are in its kernel (each
  // element's rotations are too, about its own rotated rest shape, so globally only 3 modes).
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Kw);
  const double lmax = eig.eigenvalues().maxCoeff();
  CHECK((Kw - Kw.transpose()).norm() < 1e-12 * Kw.norm());
  CHECK(eig.eigenvalues()(0) > -1e-9 * lmax);
  CHECK(eig.eigenvalues()(2) < 1e-9 * lmax);
  CHECK(eig.eigenvalues()(3) > 1e-6 * lmax);
  // At the rigidly moved rest shape all 6 rigid modes are in the kernel.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigr(Kr);
  CHECK(eigr.eigenvalues()(0) > -1e-9 * lmax);
  CHECK(eigr.eigenvalues()(5) < 1e-9 * lmax);
  CHECK(eigr.eigenvalues()(6) > 1e-6 * lmax);
}

TEST_CASE("zero elastic energy and force under random rigid motions", "[sim][corot]") {
  CorotFixture fx;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Eigen::MatrixXd R = mbi::test::random_rotation(3, seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> uni(-10.0, 10.0);
    const Eigen::RowVector3d t(uni(rng), uni(rng), uni(rng));
    const Eigen::MatrixXd X = (fx.M.U * R.transpose()).rowwise() + t;
    // Energy scale of a 1% strain: E V 1e-4; forces scale E h^2 1e-2.
    CHECK(elastic_energy(fx.rest, fx.M.T, X) < 1e-20 * fx.mat.youngs_modulus);
    CHECK(elastic_forces(fx.rest, fx.M.T, X).cwiseAbs().maxCoeff() <
          1e-9 * fx.mat.youngs_modulus * 1e-2);
  }
}

TEST_CASE("elastic energy is positive for non-rigid deformations and matches linear "
          "elasticity at small strain",
          "[sim][corot]") {
  CorotFixture fx;
  const int n = static_cast<int>(fx.M.U.rows());
  const Eigen::MatrixXd dU = perturbed(Eigen::MatrixXd::Zero(n, 3), 1e-6, 12);
  const Eigen::VectorXd u = flat(dU);
  const double lin = 0.5 * u.dot(linear_stiffness(fx.rest, fx.M.T, n) * u);
  const double cor = elastic_energy(fx.rest, fx.M.T, fx.M.U + dU);
  CHECK(lin > 0);
  CHECK(cor == Approx(lin).epsilon(1e-4));
}

TEST_CASE("lumped masses sum to density times volume", "[sim][corot]") {
  CorotFixture fx;
  const Eigen::VectorXd m = lumped_masses(fx.rest, fx.M.T, static_cast<int>(fx.M.U.rows()));
  CHECK(m.sum() == Approx(1000.0 * 1.0 * 0.8 * 1.2).epsilon(1e-12));
  CHECK(m.minCoeff() > 0);
}

TEST_CASE("bad material and degenerate elements are rejected with a clear error",
          "[sim][corot][errors]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(lame(Material{0.0, 0.3, 1000}), Error);
  CHECK_THROWS_AS(lame(Material{-1.0, 0.3, 1000}), Error);
  CHECK_THROWS_AS(lame(Material{nan, 0.3, 1000}), Error);
  CHECK_THROWS_AS(lame(Material{1e5, 0.5, 1000}), Error);
  CHECK_THROWS_AS(lame(Material{1e5, 0.7, 1000}), Error);
  CHECK_THROWS_AS(lame(Material{1e5, -1.0, 1000}), Error);
  CHECK_THROWS_AS(lame(Material{1e5, 0.3, 0.0}), Error);
  CHECK_NOTHROW(lame(Material{1e5, 0.49, 1000}));
  CHECK_NOTHROW(lame(Material{1e5, -0.9, 1000}));
  CHECK_THROWS_WITH(lame(Material{1e5, 0.5, 1000}, "element 7"),
                    Catch::Contains("element 7") && Catch::Contains("Poisson"));

  auto M = mbi::test::box_tet_mesh(1, 1, 1);
  // Flatten element 3: move its last corner onto the plane of the other three.
  Eigen::MatrixXd U = M.U;
  const Eigen::Vector4i t = M.T.row(3);
  Eigen::MatrixXi T = M.T;
  Eigen::MatrixXd U2(U.rows() + 1, 3);
  U2 << U, (0.3 * U.row(t(0)) + 0.7 * U.row(t(1)));
  T(3, 3) = static_cast<int>(U.rows());  // new node on edge t0-t1: zero volume
  CHECK_THROWS_WITH(mesh_rest(U2, T, Material{}), Catch::Contains("element 3") &&
                                                      Catch::Contains("degenerate"));
  T = M.T;
  T(2, 1) = T(2, 0);
  CHECK_THROWS_WITH(mesh_rest(U, T, Material{}), Catch::Contains("element 2"));
  T = M.T;
  T(4, 2) = 99;
  CHECK_THROWS_WITH(mesh_rest(U, T, Material{}), Catch::Contains("element 4"));
  U(5, 1) = nan;
  CHECK_THROWS_WITH(mesh_rest(U, M.T, Material{}), Catch::Contains("node 5"));
  std::vector<Material> per(M.T.rows(), Material{});
  per[2].youngs_modulus = -3;
  CHECK_THROWS_WITH(mesh_rest(M.U, M.T, Material{}, per), Catch::Contains("element 2"));
}
