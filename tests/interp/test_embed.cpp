// Embedding: barycentric coordinates, outside points, errors.
#include <mbi/interp/embed.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <catch2/catch.hpp>

#include "common/grid_meshes.hpp"

#include <algorithm>
#include <random>

using namespace mbi::interp;

namespace {
// Brute-force distance to the mesh: minimum over elements of the distance to the element,
// computed by dense sampling-free projection (quadratic program solved by enumeration of faces
// is what embed does; here: sample the element with a fine barycentric lattice -> upper bound,
// used with a tolerance of the lattice spacing).
double lattice_distance(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T, const Eigen::RowVectorXd& p,
                        int steps) {
  const int d = static_cast<int>(U.cols());
  double best = 1e300;
  for (int e = 0; e < T.rows(); ++e) {
    for (int i = 0; i <= steps; ++i)
      for (int j = 0; i + j <= steps; ++j)
        for (int k = 0; i + j + k <= steps; ++k) {
          if (d == 2 && k > 0) break;
          const double b1 = double(i) / steps, b2 = double(j) / steps, b3 = double(k) / steps;
          Eigen::RowVectorXd q = (1 - b1 - b2 - b3) * U.row(T(e, 0)) + b1 * U.row(T(e, 1)) +
                                 b2 * U.row(T(e, 2));
          if (d == 3) q += b3 * U.row(T(e, 3));
          best = std::min(best, (q - p).norm());
        }
  }
  return best;
}
}  // namespace

TEST_CASE("embedding of random inside points reproduces them", "[embed]") {
  for (int d : {2, 3}) {
    auto M = d == 3 ? mbi::test::box_tet_mesh(3, 2, 4) : mbi::test::square_tri_mesh(5, 4);
    mbi::test::jitter(M, 0.2, d == 3 ? 0.25 : 0.2, 11);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    Eigen::MatrixXd P(2000, d);
    for (int i = 0; i < P.rows(); ++i)
      for (int c = 0; c < d; ++c) P(i, c) = uni(rng);
    const Embedding emb = embed(M.U, M.T, P);
    CHECK(emb.outside.empty());  // the unit box is covered exactly
    CHECK(emb.max_outside_distance == 0.0);
    REQUIRE(emb.size() == P.rows());
    REQUIRE(emb.dim() == d);
    for (int i = 0; i < P.rows(); ++i) {
      CHECK(std::abs(emb.bary.row(i).sum() - 1.0) < 1e-12);
      CHECK(emb.bary.row(i).minCoeff() >= -1e-9);  // inside tolerance of embed()
    }
    const Eigen::MatrixXd R = embedded_positions(M.U, M.T, emb);
    CHECK((R - P).cwiseAbs().maxCoeff() < 1e-12);
    // Vertices themselves
    const Embedding ev = embed(M.U, M.T, M.U);
    CHECK((embedded_positions(M.U, M.T, ev) - M.U).cwiseAbs().maxCoeff() < 1e-12);
    CHECK(ev.outside.empty());
  }
}

TEST_CASE("outside points attach to the nearest element with the true distance", "[embed]") {
  for (int d : {2, 3}) {
    auto M = d == 3 ? mbi::test::box_tet_mesh(2, 2, 3) : mbi::test::square_tri_mesh(4, 3);
    mbi::test::jitter(M, 0.2, 0.3, 2);
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> uni(-0.6, 1.6);
    Eigen::MatrixXd P(60, d);
    for (int i = 0; i < P.rows(); ++i)
      for (int c = 0; c < d; ++c) P(i, c) = uni(rng);
    P.row(0).setConstant(25.0);  // far away: the shell search must still find the corner
    const Embedding emb = embed(M.U, M.T, P);
    int expected_outside = 0;
    double max_dist = 0;
    for (int i = 0; i < P.rows(); ++i) {
      const bool out = (P.row(i).array() < 0).any() || (P.row(i).array() > 1).any();
      expected_outside += out;
      if (!out) continue;
      // exact distance to the unit box (convex, equal to the mesh's union)
      const Eigen::RowVectorXd q = P.row(i).cwiseMax(0.0).cwiseMin(1.0);
      const double dist = (P.row(i) - q).norm();
      max_dist = std::max(max_dist, dist);
      // the attached element realises the distance: the closest point of that element
      // is within distance dist; check via a lattice sample (spacing 1/40 of an element edge)
      const Eigen::MatrixXi Te = M.T.row(emb.element(i));
      CHECK(lattice_distance(M.U, Te, P.row(i), 40) <= dist + 0.03);
      // coordinates still sum to 1 and reproduce the point by extrapolation
      CHECK(std::abs(emb.bary.row(i).sum() - 1.0) < 1e-12);
      CHECK(emb.bary.row(i).minCoeff() < 0);
    }
    CHECK(static_cast<int>(emb.outside.size()) == expected_outside);
    CHECK(emb.max_outside_distance == Approx(max_dist).epsilon(1e-9));
    const Eigen::MatrixXd R = embedded_positions(M.U, M.T, emb);
    CHECK((R - P).cwiseAbs().maxCoeff() < 1e-9);  // extrapolated coordinates reproduce P
  }
}

TEST_CASE("embedding errors", "[embed]") {
  auto M = mbi::test::box_tet_mesh(1, 1, 1);
  Eigen::MatrixXd P = Eigen::MatrixXd::Constant(4, 3, 0.5);
  P(2, 1) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(embed(M.U, M.T, P), Catch::Contains("point 2"));
  P(2, 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(embed(M.U, M.T, P), Catch::Contains("point 2"));
  CHECK_THROWS_AS(embed(M.U, M.T, Eigen::MatrixXd::Zero(3, 2)), Error);
}

TEST_CASE("points in the notch of an L-shaped mesh find the nearest element", "[embed]") {
  // 2D: 6x6 squares on [0,1]^2 without the top-right 3x3 block (an L); 3D: 4x4x2 cells without
  // the cells with x > 0.5 and y > 0.5. The notch lies inside the grid's bounding box.
  for (int d : {2, 3}) {
    const mbi::test::Mesh full = d == 2 ? mbi::test::square_tri_mesh(6, 6)
                                        : mbi::test::box_tet_mesh(4, 4, 2);
    std::vector<int> keep;
    for (int e = 0; e < full.T.rows(); ++e) {
      Eigen::RowVectorXd c = Eigen::RowVectorXd::Zero(d);
      for (int k = 0; k <= d; ++k) c += full.U.row(full.T(e, k)) / (d + 1);
      if (!(c(0) > 0.5 && c(1) > 0.5)) keep.push_back(e);
    }
    Eigen::MatrixXi T(keep.size(), d + 1);
    for (size_t i = 0; i < keep.size(); ++i) T.row(i) = full.T.row(keep[i]);
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    Eigen::MatrixXd P(300, d);
    for (int i = 0; i < P.rows(); ++i)
      for (int c = 0; c < d; ++c) P(i, c) = uni(rng);
    const Embedding emb = embed(full.U, T, P);
    double max_dist = 0;
    int expected = 0;
    for (int i = 0; i < P.rows(); ++i) {
      const bool notch = P(i, 0) > 0.5 && P(i, 1) > 0.5;
      expected += notch;
      if (!notch) continue;
      // exact distance to the L: the nearer of the two arms' boundaries x = 0.5, y = 0.5
      const double dist = std::min(P(i, 0) - 0.5, P(i, 1) - 0.5);
      max_dist = std::max(max_dist, dist);
      const Eigen::MatrixXi Te = T.row(emb.element(i));
      CHECK(lattice_distance(full.U, Te, P.row(i), 40) <= dist + 0.02);
    }
    CHECK(static_cast<int>(emb.outside.size()) == expected);
    CHECK(emb.max_outside_distance == Approx(max_dist).epsilon(1e-9));
    CHECK((embedded_positions(full.U, T, emb) - P).cwiseAbs().maxCoeff() < 1e-9);
  }
}

TEST_CASE("embedding is scale-free: tiny, huge and far-offset meshes embed like the unit mesh",
          "[embed][scale]") {
  for (int d : {2, 3}) {
    auto M = d == 3 ? mbi::test::box_tet_mesh(3, 2, 2) : mbi::test::square_tri_mesh(4, 3);
    mbi::test::jitter(M, 0.2, 0.3, 5);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> uni(-0.5, 1.5);  // inside and outside points
    Eigen::MatrixXd P(80, d);
    for (int i = 0; i < P.rows(); ++i)
      for (int c = 0; c < d; ++c) P(i, c) = uni(rng);
    const Embedding unit = embed(M.U, M.T, P);
    for (const double scale : {1e-105, 1e-9, 1e9, 1e100})
      for (const double off : {0.0, 1e3}) {  // offset in units of the model size
        INFO("d " << d << ", scale " << scale << ", offset " << off);
        const Eigen::MatrixXd U = ((M.U.array() + off) * scale).matrix();
        const Eigen::MatrixXd Q = ((P.array() + off) * scale).matrix();
        const Embedding e = embed(U, M.T, Q);
        CHECK(e.outside == unit.outside);
        // inside points: the same element and coordinates (affine invariants; the offset's
        // rounding is ~1e-16 x 1e3 relative). Outside points may tie between elements sharing
        // the nearest vertex or edge: their extrapolation must reproduce the point.
        const Eigen::MatrixXd R = embedded_positions(U, M.T, e);
        for (int i = 0; i < P.rows(); ++i) {
          if (std::find(unit.outside.begin(), unit.outside.end(), i) == unit.outside.end()) {
            CHECK(e.element(i) == unit.element(i));
            CHECK((e.bary.row(i) - unit.bary.row(i)).cwiseAbs().maxCoeff() < 1e-10);
          }
          CHECK((R.row(i) - Q.row(i)).cwiseAbs().maxCoeff() < 1e-9 * scale);
        }
        CHECK(e.max_outside_distance == Approx(unit.max_outside_distance * scale).epsilon(1e-9));
        CHECK((e.gradients * scale - unit.gradients).cwiseAbs().maxCoeff() <
              1e-9 * unit.gradients.cwiseAbs().maxCoeff());
        CHECK(e.gradients.allFinite());
      }
  }
}

TEST_CASE("points too far from the control mesh are refused by index, never element -1",
          "[embed][scale]") {
  auto M = mbi::test::box_tet_mesh(1, 1, 1);
  for (const double far : {1e13, 1e155, 1e160, 1e300, -1.7e308}) {
    Eigen::MatrixXd P = Eigen::MatrixXd::Constant(3, 3, 0.5);
    P(1, 0) = far;  // squared distances overflowed from ~1e154 on: no element chosen, -1 used
    INFO("far " << far);
    CHECK_THROWS_WITH(embed(M.U, M.T, P), Catch::Contains("point 1") && Catch::Contains("too far"));
  }
  // a tiny mesh: (p - centre) / size overflows to inf for a large finite point
  const Eigen::MatrixXd tiny = M.U * 1e-300;
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(2, 3);
  P(0, 2) = 1e10;
  CHECK_THROWS_WITH(embed(tiny, M.T, P), Catch::Contains("point 0"));
  // within the limit: attached to the nearest element with the true distance (1e11 - 1)
  P = Eigen::MatrixXd::Constant(1, 3, 0.5);
  P(0, 1) = 1e11;
  const Embedding e = embed(M.U, M.T, P);
  REQUIRE(e.outside.size() == 1);
  CHECK(e.element(0) >= 0);
  CHECK(e.max_outside_distance == Approx(1e11 - 1).epsilon(1e-12));
  CHECK(embedded_positions(M.U, M.T, e)(0, 1) == Approx(1e11).epsilon(1e-9));
  // a control mesh with no extent
  const Eigen::MatrixXd point = Eigen::MatrixXd::Constant(M.U.rows(), 3, 2.0);
  CHECK_THROWS_WITH(embed(point, M.T, P), Catch::Contains("no extent"));
}

TEST_CASE("deformation is scale-free: modified-BI of a tiny, huge or far-offset model is the unit "
          "result scaled", "[embed][scale]") {
  auto M = mbi::test::box_tet_mesh(2, 2, 3);
  mbi::test::jitter(M, 0.2, 0.3, 3);
  // a smooth non-affine deformation of the control vertices (bend and twist)
  auto deform = [](const Eigen::MatrixXd& U) {
    Eigen::MatrixXd X = U;
    for (int i = 0; i < U.rows(); ++i) {
      const double a = 0.6 * U(i, 2);
      X(i, 0) = std::cos(a) * U(i, 0) - std::sin(a) * U(i, 1) + 0.2 * U(i, 2) * U(i, 2);
      X(i, 1) = std::sin(a) * U(i, 0) + std::cos(a) * U(i, 1);
    }
    return X;
  };
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> uni(0.02, 0.98);
  Eigen::MatrixXd P(200, 3);
  for (int i = 0; i < P.rows(); ++i)
    for (int c = 0; c < 3; ++c) P(i, c) = uni(rng);
  auto run = [&](const Eigen::MatrixXd& U, const Eigen::MatrixXd& X, const Eigen::MatrixXd& Q) {
    const ModifiedBI mb(U, M.T);
    const BezierPoints B = mb.bezier(X, mb.solve(X));
    Eigen::MatrixXd out;
    evaluate<double>(B, embed(U, M.T, Q), out);
    return out;
  };
  const Eigen::MatrixXd X = deform(M.U);
  const Eigen::MatrixXd unit = run(M.U, X, P);
  REQUIRE(unit.allFinite());
  for (const double scale : {1e-9, 1e9})
    for (const double off : {0.0, 1e3}) {  // offset in units of the model size
      INFO("scale " << scale << ", offset " << off);
      auto place = [&](const Eigen::MatrixXd& A) { return Eigen::MatrixXd((A.array() + off) * scale); };
      const Eigen::MatrixXd out = run(place(M.U), place(X), place(P));
      // relative to the model size: the offset costs ~1e-16 x 1e3 of rounding, conditioning more
      CHECK((out - place(unit)).cwiseAbs().maxCoeff() < 1e-8 * scale);
    }
}
