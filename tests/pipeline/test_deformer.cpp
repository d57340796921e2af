// The Deformer against the frame pipeline (the same positions and normals for every method), its
// batch calls against single poses, and its vjp against finite differences, in 2D and 3D.
#include <catch2/catch.hpp>

#include <mbi/interp.hpp>
#include <mbi/pipeline/deformer.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include "common/grid_meshes.hpp"

#include <limits>
#include <random>
#include <string>
#include <vector>

using namespace mbi;
using pipeline::Deformer;
using pipeline::Method;

namespace {

test::Mesh mesh(int d) {
  test::Mesh m = d == 3 ? test::box_tet_mesh(4, 2, 2, Eigen::Vector3d(2, 1, 1)) : test::square_tri_mesh(5, 3);
  test::jitter(m, 0.15, d == 3 ? 0.5 : 0.2, 3);
  return m;
}

Eigen::MatrixXd random(Eigen::Index r, Eigen::Index c, unsigned seed, double lo = -1, double hi = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(lo, hi);
  Eigen::MatrixXd A(r, c);
  for (Eigen::Index i = 0; i < r; ++i)
    for (Eigen::Index j = 0; j < c; ++j) A(i, j) = uni(rng);
  return A;
}

// Points in the bounding box (a few slightly outside it, extrapolated).
Eigen::MatrixXd points_in(const Eigen::MatrixXd& U, int p, unsigned seed) {
  const Eigen::RowVectorXd lo = U.colwise().minCoeff(), hi = U.colwise().maxCoeff();
  Eigen::MatrixXd P = random(p, U.cols(), seed, -0.02, 1.02);
  for (int i = 0; i < p; ++i) P.row(i) = lo.array() + P.row(i).array() * (hi - lo).array();
  return P;
}

// A pose: a smooth bend plus noise.
Eigen::MatrixXd pose(const Eigen::MatrixXd& U, unsigned seed) {
  Eigen::MatrixXd X = U + 0.05 * random(U.rows(), U.cols(), seed);
  for (Eigen::Index i = 0; i < U.rows(); ++i) X(i, 1) += 0.3 * U(i, 0) * U(i, 0);
  return X;
}

double max_abs(const Eigen::MatrixXd& A) { return A.size() ? A.cwiseAbs().maxCoeff() : 0.0; }

Eigen::MatrixXd unit_rows(Eigen::MatrixXd N) {
  for (Eigen::Index i = 0; i < N.rows(); ++i) N.row(i).normalize();
  return N;
}

}  // namespace

TEST_CASE("deformer: the same positions and normals as the frame pipeline, every method", "[deformer]") {
  for (int d : {2, 3})
    for (Method method : pipeline::all_methods()) {
      INFO(d << "D, " << pipeline::method_name(method));
      const test::Mesh m = mesh(d);
      const Eigen::MatrixXd P = points_in(m.U, 300, 5);
      const Eigen::MatrixXd N = unit_rows(random(300, d, 6));
      const Eigen::MatrixXd X = pose(m.U, 7);
      const Deformer deformer(m.U, m.T, P, {.method = method}, N);
      pipeline::FramePipeline pipe(m.U, m.T, interp::embed(m.U, m.T, P),
                                   std::make_unique<pipeline::GivenDriver>(std::vector<Eigen::MatrixXd>{X}),
                                   {.method = method, .interp = {}, .normals = true}, nullptr, N);
      REQUIRE(pipe.step().ok);
      Eigen::MatrixXd positions(300, d), normals(300, d);
      deformer.deform(X, positions, normals);
      CHECK(max_abs(positions - pipe.positions()) == 0.0);
      CHECK(max_abs(normals - pipe.normals()) == 0.0);
      CHECK(max_abs(deformer.deform(X) - positions) == 0.0);
      CHECK(max_abs(deformer.M(X) - pipe.M()) == 0.0);
      CHECK(max_abs(deformer.bezier(X) - pipe.bezier()) == 0.0);
      // the rest pose gives the points back (every method reproduces affine maps)
      CHECK(max_abs(deformer.deform(m.U) - P) < 1e-12);
    }
}

TEST_CASE("deformer: the float kernel agrees with the exact positions to float round-off", "[deformer]") {
  for (int d : {2, 3}) {
    const test::Mesh m = mesh(d);
    const Eigen::MatrixXd P = points_in(m.U, 500, 8);
    Deformer deformer(m.U, m.T, P, {.method = Method::ModifiedBI}, unit_rows(random(500, d, 9)));
    const Eigen::MatrixXd X = pose(m.U, 10);
    Eigen::MatrixXd positions(500, d), normals(500, d);
    deformer.deform(X, positions, normals);
    interp::RowMatrixXf pf(500, d), nf(500, d);
    deformer.deform_float(X, pf);
    CHECK(max_abs(pf.cast<double>() - positions) < 1e-5);
    deformer.deform_float(X, pf, nf);
    CHECK(max_abs(pf.cast<double>() - positions) < 1e-5);
    CHECK(max_abs(nf.cast<double>() - normals) < 1e-4);
  }
}

TEST_CASE("deformer: a batch equals its poses one by one", "[deformer]") {
  for (int d : {2, 3}) {
    const test::Mesh m = mesh(d);
    const Eigen::Index n = m.U.rows(), p = 200;
    const Deformer deformer(m.U, m.T, points_in(m.U, 200, 11));
    const int frames = 3;
    Eigen::MatrixXd X(frames * n, d), G = random(frames * p, d, 12);
    for (int k = 0; k < frames; ++k) X.middleRows(k * n, n) = pose(m.U, 13 + k);
    Eigen::MatrixXd positions(frames * p, d), dX(frames * n, d);
    deformer.deform_batch(X, positions);
    deformer.vjp_batch(G, dX);
    for (int k = 0; k < frames; ++k) {
      CHECK(max_abs(positions.middleRows(k * p, p) - deformer.deform(X.middleRows(k * n, n))) == 0.0);
      CHECK(max_abs(dX.middleRows(k * n, n) - deformer.vjp(G.middleRows(k * p, p))) == 0.0);
    }
    CHECK_THROWS_AS(deformer.deform_batch(X.topRows(n + 1), positions), Error);
    CHECK_THROWS_AS(deformer.vjp_batch(G, dX.topRows(n)), Error);
  }
}

// Strided views, as numpy hands a C-order array to the bindings: rows `cols + gap` doubles apart,
// columns one apart, in a buffer with a gap after each row.
struct DeformerStrided {
  std::vector<double> buffer;
  Eigen::Index rows, cols, pitch;
  DeformerStrided(Eigen::Index r, Eigen::Index c, Eigen::Index gap) : buffer(r * (c + gap), -7.0), rows(r), cols(c), pitch(c + gap) {}
  interp::PointsRef<double> view() {
    return Eigen::Map<Eigen::MatrixXd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>(
        buffer.data(), rows, cols, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(1, pitch));
  }
};

TEST_CASE("deformer: a batch in blocks of frames equals its poses one by one, strided, every method and solve path",
          "[deformer]") {
  for (int d : {2, 3})
    for (Method method : pipeline::all_methods())
      for (interp::SolvePath path : {interp::SolvePath::Dense, interp::SolvePath::Sparse}) {
        if (method != Method::ModifiedBI && path == interp::SolvePath::Sparse) continue;
        INFO(d << "D, " << pipeline::method_name(method) << ", " << interp::kSolvePathNames.name(path));
        const test::Mesh m = mesh(d);
        const Eigen::Index n = m.U.rows(), p = 150;
        pipeline::DeformerOptions options{.method = method};
        options.interp.solve_path = path;
        const Deformer deformer(m.U, m.T, points_in(m.U, static_cast<int>(p), 41), options);
        // 19 frames: two blocks of 8 and 3 on the dense operator, 9 pairs and one (3D) or 4 fours
        // and 3 (2D) on the factor
        const Eigen::Index frames = 19;
        DeformerStrided X(frames * n, d, 1), positions(frames * p, d, 2);
        for (Eigen::Index k = 0; k < frames; ++k) X.view().middleRows(k * n, n) = pose(m.U, 50 + static_cast<unsigned>(k));
        deformer.deform_batch(X.view(), positions.view());
        double worst = 0, scale = 0;
        for (Eigen::Index k = 0; k < frames; ++k) {
          const Eigen::MatrixXd one = deformer.deform(Eigen::MatrixXd(X.view().middleRows(k * n, n)));
          worst = std::max(worst, max_abs(positions.view().middleRows(k * p, p) - one));
          scale = std::max(scale, max_abs(one));
        }
        CHECK(worst <= 1e-12 * scale);
        for (Eigen::Index i = 0; i < frames * p; ++i) CHECK(positions.buffer[i * positions.pitch + d] == -7.0);
        if (method != Method::ModifiedBI) continue;
        // the solver's batch, M pose by pose, and its check naming the pose
        const interp::ModifiedBI& solver = deformer.solver();
        Eigen::MatrixXd M(frames * n * d, d);
        solver.solve_batch(X.view(), M);
        double worst_m = 0, scale_m = 0;
        for (Eigen::Index k = 0; k < frames; ++k) {
          const Eigen::MatrixXd one = solver.solve(Eigen::MatrixXd(X.view().middleRows(k * n, n)));
          worst_m = std::max(worst_m, max_abs(M.middleRows(k * n * d, n * d) - one));
          scale_m = std::max(scale_m, max_abs(one));
        }
        CHECK(scale_m > 0);
        CHECK(worst_m <= 1e-12 * scale_m);
        X.view()(7 * n + 3, 1) = std::numeric_limits<double>::infinity();
        CHECK_THROWS_WITH(solver.solve_batch(X.view(), M), Catch::Contains("control vertex 3 of pose 7"));
        CHECK_THROWS_WITH(deformer.deform_batch(X.view(), positions.view()), Catch::Contains("control vertex 3 of pose 7"));
        CHECK_THROWS_AS(solver.solve_batch(X.view().topRows(n + 1), M), Error);
        CHECK_THROWS_AS(solver.solve_batch(X.view(), M.topRows(n * d)), Error);
      }
}

TEST_CASE("deformer: vjp against finite differences, every method, 2D and 3D", "[deformer]") {
  for (int d : {2, 3})
    for (Method method : pipeline::all_methods()) {
      INFO(d << "D, " << pipeline::method_name(method));
      const test::Mesh m = mesh(d);
      const Eigen::MatrixXd P = points_in(m.U, 150, 20);
      const Deformer deformer(m.U, m.T, P, {.method = method});
      const Eigen::MatrixXd X = pose(m.U, 21), G = random(150, d, 22);
      const Eigen::MatrixXd dX = deformer.vjp(G);
      // L(X) = <G, deform(X)> is linear in X: central differences are exact but for round-off
      auto L = [&](const Eigen::MatrixXd& Y) { return (G.array() * deformer.deform(Y).array()).sum(); };
      const double h = 1e-3;
      double worst = 0;
      for (Eigen::Index i = 0; i < X.rows(); i += 3)
        for (int c = 0; c < d; ++c) {
          Eigen::MatrixXd Xp = X, Xm = X;
          Xp(i, c) += h;
          Xm(i, c) -= h;
          worst = std::max(worst, std::abs((L(Xp) - L(Xm)) / (2 * h) - dX(i, c)));
        }
      CHECK(worst < 1e-9 * (1 + max_abs(dX)));
      // and in a random direction, through every vertex at once
      const Eigen::MatrixXd V = random(X.rows(), d, 23);
      const double fd = (L(X + h * V) - L(X - h * V)) / (2 * h);
      CHECK(std::abs(fd - (dX.array() * V.array()).sum()) < 1e-9 * (1 + std::abs(fd)));
      // the vjp does not depend on the pose (the map is linear)
      CHECK(max_abs(deformer.vjp(G) - dX) == 0.0);
    }
}

TEST_CASE("deformer: refuses wrong sizes, NaN and what the method lacks", "[deformer]") {
  const test::Mesh m = mesh(3);
  const Eigen::MatrixXd P = points_in(m.U, 50, 30);
  Deformer bi(m.U, m.T, P, {.method = Method::BI});
  Eigen::MatrixXd X = m.U, out(50, 3);
  CHECK_THROWS_AS(bi.deform(X.topRows(3), out), Error);
  CHECK_THROWS_AS(bi.deform(X, out.topRows(49)), Error);
  X(2, 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(bi.deform(X, out), Catch::Contains("control vertex 2"));
  CHECK_THROWS_WITH(bi.deform(m.U, out, out), Catch::Contains("no rest normals"));
  CHECK_THROWS_AS(bi.solver(), Error);
  CHECK_THROWS_AS(bi.phong(), Error);
  CHECK_THROWS_AS(bi.set_alpha(0.2), Error);
  CHECK_THROWS_AS(bi.vjp(Eigen::MatrixXd::Zero(49, 3)), Error);
  CHECK_THROWS_AS(Deformer(m.U, m.T, P, {.threads = -1}), Error);
  CHECK_THROWS_AS(Deformer(m.U, m.T, P, {}, Eigen::MatrixXd::Ones(3, 3)), Error);
  Eigen::MatrixXi T = m.T;
  T(0, 0) = static_cast<int>(m.U.rows());
  CHECK_THROWS_AS(Deformer(m.U, T, P), Error);
  Deformer mbi(m.U, m.T, P);
  mbi.set_alpha(0.3);
  CHECK(mbi.solver().alpha() == 0.3);
  CHECK(mbi.options().interp.alpha == 0.3);
  CHECK_THROWS_AS(mbi.set_alpha(-1), Error);
}
