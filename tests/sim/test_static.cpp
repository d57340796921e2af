// Static solves: patch test, cantilever against Euler-Bernoulli, co-rotational vs linear, scale
// and node-order robustness.
#include <catch2/catch.hpp>

#include "sim_helpers.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

using namespace mbi::sim;
using mbi::test::nodes_at;

namespace {

struct BeamResult {
  double ratio;       // tip deflection / Euler-Bernoulli
  double corot_tip;   // m
  double linear_tip;  // m
};

// Cantilever of length L = 10 h fixed at x = 0 under gravity (-y), nu = 0.3.
BeamResult cantilever(int cells, double L, double E) {
  const double h = L / 10.0;
  const auto M = mbi::test::bar(10 * cells, cells, cells, L, h);
  const Material mat{E, 0.3, 1000.0};
  Parameters p;
  p.gravity = Eigen::Vector3d(0, -9.81, 0);
  Simulator sim(M.U, M.T, mat, p);
  const auto fixed = nodes_at(M.U, 0, 0.0);
  sim.fix(fixed);
  const StaticResult st = sim.solve_static(50);
  INFO(st.message);
  REQUIRE(st.converged);
  Eigen::MatrixXd fixed_pos(fixed.size(), 3);
  for (size_t j = 0; j < fixed.size(); ++j) fixed_pos.row(j) = M.U.row(fixed[j]);
  const Eigen::MatrixXd Xlin = mbi::test::linear_static(M, mat, p.gravity, fixed, fixed_pos);
  const double q = 1000.0 * 9.81 * h * h;  // N/m
  const double I = h * h * h * h / 12.0;
  const double eb = q * L * L * L * L / (8.0 * E * I);
  BeamResult r;
  r.corot_tip = -mbi::test::tip_deflection(M.U, sim.positions(), L);
  r.linear_tip = -mbi::test::tip_deflection(M.U, Xlin, L);
  r.ratio = r.corot_tip / eb;
  return r;
}

}  // namespace

TEST_CASE("patch test: a linear field imposed on the boundary is reproduced inside",
          "[sim][static]") {
  auto M = mbi::test::box_tet_mesh(4, 3, 3, Eigen::Vector3d(1.0, 0.75, 0.9));
  mbi::test::jitter(M, 0.2, 0.25, 17);  // irregular interior
  Eigen::Matrix3d A;
  A << 1.05, 0.08, -0.03, -0.06, 0.97, 0.04, 0.02, 0.05, 1.1;  // stretch + shear + rotation
  const Eigen::Vector3d b(0.1, -0.2, 0.3);
  Parameters p;
  p.gravity.setZero();
  Simulator sim(M.U, M.T, Material{1e6, 0.4, 1000}, p);
  // Boundary nodes: on the bounding box. Move them to the affine image first, then fix.
  std::vector<int> boundary;
  std::vector<char> is_boundary(M.U.rows(), 0);
  const Eigen::RowVector3d lo = M.U.colwise().minCoeff(), hi = M.U.colwise().maxCoeff();
  for (Eigen::Index i = 0; i < M.U.rows(); ++i)
    for (int c = 0; c < 3; ++c)
      if (std::abs(M.U(i, c) - lo(c)) < 1e-12 || std::abs(M.U(i, c) - hi(c)) < 1e-12)
        is_boundary[i] = 1;
  Eigen::MatrixXd X = M.U;
  for (Eigen::Index i = 0; i < M.U.rows(); ++i)
    if (is_boundary[i]) {
      boundary.push_back(static_cast<int>(i));
      X.row(i) = (A * M.U.row(i).transpose() + b).transpose();
    }
  REQUIRE(boundary.size() < static_cast<size_t>(M.U.rows()));
  sim.set_positions(X);
  sim.fix(boundary);
  const StaticResult st = sim.solve_static(100);
  INFO(st.message);
  REQUIRE(st.converged);
  double err = 0.0;
  for (Eigen::Index i = 0; i < M.U.rows(); ++i)
    err = std::max(err, (sim.positions().row(i).transpose() - (A * M.U.row(i).transpose() + b)).norm());
  CHECK(err < 1e-9);
}

TEST_CASE("cantilever under gravity converges toward Euler-Bernoulli, co-rotational equals "
          "linear at small load",
          "[sim][static][cantilever][long]") {
  // L = 1 m, h = 0.1 m, E = 1e9 Pa: tip deflection ~1.5e-3 L (small load).
  //
  // Limit: Euler-Bernoulli plus Timoshenko shear, w_s / w_b = E h^2 / (3 k G L^2) ~ 0.01 for
  // L / h = 10, nu = 0.3 (k = 5/6), so the 3D answer is ~1.01 EB; displacement-based FEM is
  // too stiff and approaches it from below.
  // Coarse meshes: linear tetrahedra in bending carry parasitic shear, the classic locking
  // model gives tip / EB ~ 1 / (1 + c / n^2) with n elements through the depth and c an O(1)
  // constant of the element shape and nu. The bands below are that model for c in [2.5, 5]
  // (n = 2: 0.44-0.62, n = 4: 0.76-0.87, n = 6: 0.88-0.94); the measured ratios fit c ~ 4.
  // Co-rotational vs linear: at a tip rotation theta ~ 2e-3 rad the geometric non-linearity is
  // O(theta^2) ~ 4e-6 relative, far below 1e-4.
  const double c_lo = 2.5, c_hi = 5.0;
  double previous = 0.0;
  for (int cells : {2, 4, 6}) {
    const BeamResult r = cantilever(cells, 1.0, 1e9);
    const double n2 = cells * cells;
    const double rel = std::abs(r.corot_tip - r.linear_tip) / r.linear_tip;
    INFO("cantilever " << cells << "x" << cells << "x" << 10 * cells
                       << " cells: tip/Euler-Bernoulli = " << r.ratio
                       << " (locking constant c = " << n2 * (1.0 / r.ratio - 1.0)
                       << "), |corot - linear| / linear = " << rel);
    CHECK(r.corot_tip < 2e-3);  // m: small load indeed
    CHECK(r.ratio > previous);  // monotone under refinement
    CHECK(r.ratio < 1.02);      // linear tets are too stiff, never softer than the beam
    CHECK(r.ratio > n2 / (n2 + c_hi));
    CHECK(r.ratio < n2 / (n2 + c_lo));
    CHECK(rel < 1e-4);
    previous = r.ratio;
  }
  CHECK(previous >= 0.85);
}

TEST_CASE("scale robustness: 1 mm and 100 m cantilevers give the same relative deflection",
          "[sim][static][scale][long]") {
  // E proportional to L keeps the relative deflection q L^3 / (8 E I) fixed.
  const BeamResult small = cantilever(2, 1e-3, 1e6);
  const BeamResult big = cantilever(2, 100.0, 1e11);
  CHECK(small.ratio == Approx(big.ratio).epsilon(0.01));
  CHECK(small.corot_tip / 1e-3 == Approx(big.corot_tip / 100.0).epsilon(0.01));
  // ... and dynamically stable at both scales at dt = 1/60 s.
  for (double L : {1e-3, 100.0}) {
    const auto M = mbi::test::bar(20, 2, 2, L, L / 10);
    Parameters p;
    p.mass_damping = 1.0;
    Simulator sim(M.U, M.T, Material{1e9 * L, 0.3, 1000}, p);
    sim.fix(nodes_at(M.U, 0, 0.0));
    for (int s = 0; s < 120; ++s) REQUIRE(sim.step().success);
    const double rel = -mbi::test::tip_deflection(M.U, sim.positions(), L) / L;
    CHECK(std::isfinite(rel));
    CHECK(rel > 0);
    CHECK(rel < 0.01);
  }
}

TEST_CASE("node order and tetrahedron orientation change nothing beyond round-off",
          "[sim][static][order]") {
  const auto M = mbi::test::bar(12, 2, 2, 1.0, 0.1);
  const int n = static_cast<int>(M.U.rows());
  const Material mat{1e7, 0.45, 1000};  // deflection ~0.1 L: non-linear regime
  std::mt19937 rng(23);
  std::vector<int> perm(n);  // new index of old node i
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  Eigen::MatrixXd U2(n, 3);
  for (int i = 0; i < n; ++i) U2.row(perm[i]) = M.U.row(i);
  std::vector<int> eorder(M.T.rows());
  std::iota(eorder.begin(), eorder.end(), 0);
  std::shuffle(eorder.begin(), eorder.end(), rng);
  Eigen::MatrixXi T2(M.T.rows(), 4);
  for (Eigen::Index e = 0; e < M.T.rows(); ++e) {
    Eigen::Vector4i t = M.T.row(eorder[e]);
    for (int a = 0; a < 4; ++a) t(a) = perm[t(a)];
    std::rotate(t.data(), t.data() + (e % 4), t.data() + 4);
    if (e % 2) std::swap(t(0), t(1));  // inverted orientation
    T2.row(e) = t.transpose();
  }
  Parameters p;
  Simulator a(M.U, M.T, mat, p), b(U2, T2, mat, p);
  std::vector<int> fa = nodes_at(M.U, 0, 0.0), fb;
  for (int i : fa) fb.push_back(perm[i]);
  a.fix(fa);
  b.fix(fb);
  auto compare = [&] {
    double err = 0.0;
    for (int i = 0; i < n; ++i) err = std::max(err, (a.positions().row(i) - b.positions().row(perm[i])).norm());
    return err;
  };
  for (int s = 0; s < 30; ++s) {
    REQUIRE(a.step().success);
    REQUIRE(b.step().success);
  }
  const double swing = (a.positions() - M.U).cwiseAbs().maxCoeff();
  CHECK(swing > 0.02);  // really deformed
  CHECK(compare() < 1e-9 * swing);
  REQUIRE(a.solve_static(100).converged);
  REQUIRE(b.solve_static(100).converged);
  CHECK(compare() < 1e-9);
}
