// Evaluation kernel: float vs double, threads, BI, outside points, errors.
#include <catch2/catch.hpp>

#include "test_support.hpp"

#include <algorithm>
#include <limits>
#include <vector>

using namespace mbi::interp;
using namespace mbi::test;

namespace {
struct Setup {
  Mesh M;
  Eigen::MatrixXd X, P;
  VertexMatrices Mm;
  BezierPoints B;
  Embedding emb;
};

Setup make(int d, int points, double lo = 0.0, double hi = 1.0) {
  Setup s;
  s.M = jittered_mesh(d, 40);
  s.X = smooth_deform(s.M.U, 0.5);
  const ModifiedBI mbi(s.M.U, s.M.T);
  s.Mm = mbi.solve(s.X);
  s.B = mbi.bezier(s.X, s.Mm);
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> uni(lo, hi);
  s.P.resize(points, d);
  for (int i = 0; i < points; ++i)
    for (int c = 0; c < d; ++c) s.P(i, c) = uni(rng);
  s.emb = embed(s.M.U, s.M.T, s.P);
  return s;
}
}  // namespace

TEST_CASE("float and double evaluation agree to 1e-5 relative, threads do not change results", "[evaluate]") {
  for (int d : {2, 3}) {
    const Setup s = make(d, 20000);
    Eigen::MatrixXd pd, nd;
    Eigen::MatrixXf pf, nf;
    Eigen::MatrixXd nr = random_matrix(s.P.rows(), d, 42);
    nr.rowwise().normalize();
    const Eigen::MatrixXf nrf = nr.cast<float>();
    evaluate<double>(s.B, s.emb, nr, pd, nd, 0);
    evaluate<float>(s.B, s.emb, nrf, pf, nf, 0);
    const double scale = pd.cwiseAbs().maxCoeff();
    CHECK((pf.cast<double>() - pd).cwiseAbs().maxCoeff() / scale < 1e-5);
    CHECK((nf.cast<double>() - nd).cwiseAbs().maxCoeff() < 1e-5);  // unit vectors
    for (int threads : {1, 3, 8}) {
      Eigen::MatrixXd pt;
      evaluate<double>(s.B, s.emb, pt, threads);
      CHECK((pt - pd).cwiseAbs().maxCoeff() == 0.0);  // same arithmetic per point
    }
  }
}

TEST_CASE("BI is the same kernel with M = 0 and equals linear interpolation", "[evaluate]") {
  for (int d : {2, 3}) {
    const Setup s = make(d, 3000);
    const VertexMatrices Z = VertexMatrices::Zero(s.Mm.rows(), d);
    const BezierPoints Bb = bezier_bi(s.X, s.M.T);
    CHECK((Bb - bezier_points(s.M.U, s.M.T, s.X, Z)).cwiseAbs().maxCoeff() == 0.0);
    Eigen::MatrixXd p;
    evaluate<double>(Bb, s.emb, p, 2);
    const Eigen::MatrixXd lin = embedded_positions(s.X, s.M.T, s.emb);  // sum_k b_k x_k
    CHECK((p - lin).cwiseAbs().maxCoeff() < 1e-12);
  }
}

TEST_CASE("outside points are extrapolated with the element's quadratic", "[evaluate]") {
  for (int d : {2, 3}) {
    const Setup s = make(d, 400, -0.3, 1.3);
    REQUIRE(!s.emb.outside.empty());
    Eigen::MatrixXd p;
    evaluate<double>(s.B, s.emb, p, 2);
    double err = 0;
    for (int i : s.emb.outside) {
      const Eigen::VectorXd ref =
          evaluate_reference(s.M.U, s.M.T, s.X, s.Mm, s.emb.element(i), s.P.row(i).transpose());
      err = std::max(err, (p.row(i).transpose() - ref).norm());
    }
    CHECK(err < 1e-12);
  }
}

TEST_CASE("evaluate rejects inconsistent input", "[evaluate]") {
  Setup s = make(3, 50);
  Eigen::MatrixXd p, n;
  Embedding bad = s.emb;
  bad.element(7) = static_cast<int>(s.M.T.rows());
  CHECK_THROWS_WITH(evaluate<double>(s.B, bad, p), Catch::Contains("point 7"));
  CHECK_THROWS_AS(evaluate<double>(s.B.topRows(s.B.rows() - 1), s.emb, p), Error);
  Embedding nograd = s.emb;
  nograd.gradients.resize(0, 0);
  const Eigen::MatrixXd nr = Eigen::MatrixXd::Constant(50, 3, 1.0 / std::sqrt(3.0));
  CHECK_THROWS_WITH(evaluate<double>(s.B, nograd, nr, p, n), Catch::Contains("gradients"));
  CHECK_THROWS_AS(evaluate<double>(s.B, s.emb, nr.topRows(10), p, n), Error);
  CHECK_THROWS_AS(jacobian(s.M.U, s.M.T, s.B, -1, Eigen::Vector4d(0.25, 0.25, 0.25, 0.25)), Error);
}

TEST_CASE("evaluate and FastEvaluator read the Bezier points in any layout: row-major, a column block, every other row",
          "[evaluate]") {
  for (int d : {2, 3}) {
    const Setup s = make(d, 3000);
    Eigen::MatrixXd nr = random_matrix(s.P.rows(), d, 43);
    nr.rowwise().normalize();
    Eigen::MatrixXd p0, n0;
    Eigen::MatrixXf f0;
    evaluate<double>(s.B, s.emb, nr, p0, n0, 2);
    evaluate<float>(s.B, s.emb, f0, 2);
    using Strided = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows = s.B;  // a C-order array
    Eigen::MatrixXd wide = Eigen::MatrixXd::Constant(s.B.rows() + 3, d + 2, std::nan(""));
    wide.block(3, 1, s.B.rows(), d) = s.B;
    Eigen::MatrixXd twice = Eigen::MatrixXd::Constant(2 * s.B.rows(), d, std::nan(""));
    for (Eigen::Index r = 0; r < s.B.rows(); ++r) twice.row(2 * r) = s.B.row(r);
    const Strided layouts[] = {
        Strided(rows.data(), s.B.rows(), d, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(1, d)),
        Strided(wide.data() + wide.rows() + 3, s.B.rows(), d, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(wide.rows(), 1)),
        Strided(twice.data(), s.B.rows(), d, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(twice.rows(), 2))};
    FastEvaluator fast(s.emb, 2);
    fast.set_rest_normals(nr);
    RowMatrixXf fp0, fn0;
    fast.evaluate(s.B, fp0, fn0);
    for (const Strided& B : layouts) {
      INFO(d << "D, strides " << B.innerStride() << ", " << B.outerStride());
      Eigen::MatrixXd p, n;
      Eigen::MatrixXf f;
      evaluate<double>(B, s.emb, nr, p, n, 2);
      evaluate<float>(B, s.emb, f, 2);
      CHECK((p - p0).cwiseAbs().maxCoeff() == 0.0);
      CHECK((n - n0).cwiseAbs().maxCoeff() == 0.0);
      CHECK((f - f0).cwiseAbs().maxCoeff() == 0.0f);
      RowMatrixXf fp, fn;
      fast.evaluate(B, fp, fn);
      CHECK((fp - fp0).cwiseAbs().maxCoeff() == 0.0f);
      CHECK((fn - fn0).cwiseAbs().maxCoeff() == 0.0f);
    }
  }
}

TEST_CASE("a subset of the points evaluates to the full evaluation's rows, to the bit, and its transpose is the full one's "
          "with the other rows of dL/dpositions zero, the same on every thread count",
          "[evaluate][adjoint]") {
  for (int d : {2, 3}) {
    const Setup s = make(d, 20000);
    Eigen::MatrixXd full;
    evaluate<double>(s.B, s.emb, full, 1);
    const int m = static_cast<int>(s.M.T.rows());
    // 7,000 picks with repeats in random order, and the same grouped by element (runs of one element)
    std::mt19937 rng(7);
    std::uniform_int_distribution<Eigen::Index> pick(0, s.emb.size() - 1);
    std::vector<Eigen::Index> shuffled(7000);
    for (Eigen::Index& p : shuffled) p = pick(rng);
    std::vector<Eigen::Index> grouped = shuffled;
    std::stable_sort(grouped.begin(), grouped.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return s.emb.element(a) < s.emb.element(b); });
    for (const std::vector<Eigen::Index>* points : {&shuffled, &grouped}) {
      const Eigen::Index n = static_cast<Eigen::Index>(points->size());
      const Eigen::MatrixXd G = random_matrix(n, d, 3);
      Eigen::MatrixXd Gfull = Eigen::MatrixXd::Zero(s.emb.size(), d);
      for (Eigen::Index i = 0; i < n; ++i) Gfull.row((*points)[static_cast<size_t>(i)]) += G.row(i);
      const BezierPoints want = evaluate_transpose(s.emb, Gfull, m, 1);
      BezierPoints first;
      for (int threads : {1, 2, 3, 8}) {
        Eigen::MatrixXd sub(n, d);
        evaluate(s.B, s.emb, *points, sub, threads);
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows(n, d);  // another layout
        evaluate(s.B, s.emb, *points, Eigen::Map<Eigen::MatrixXd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>(
                                          rows.data(), n, d, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>(1, d)),
                 threads);
        double worst = 0.0;
        for (Eigen::Index i = 0; i < n; ++i)
          worst = std::max(worst, (sub.row(i) - full.row((*points)[static_cast<size_t>(i)])).cwiseAbs().maxCoeff());
        CHECK(worst == 0.0);
        CHECK((rows - sub).cwiseAbs().maxCoeff() == 0.0);
        BezierPoints GB(want.rows(), d);
        GB.setConstant(7.0);  // the listed points' elements' rows overwritten, the others kept
        evaluate_transpose(s.emb, *points, G, m, GB, threads);
        std::vector<char> listed(static_cast<size_t>(m), 0);
        for (Eigen::Index p : *points) listed[static_cast<size_t>(s.emb.element(p))] = 1;
        const int K = (d + 1) * (d + 2) / 2;
        for (int e = 0; e < m; ++e)
          if (!listed[static_cast<size_t>(e)]) {
            CHECK(GB.middleRows(e * K, K).isConstant(7.0));
            GB.middleRows(e * K, K).setZero();
          }
        CHECK((GB - want).cwiseAbs().maxCoeff() <= 1e-12 * (1.0 + want.cwiseAbs().maxCoeff()));
        if (threads == 1) first = GB;
        CHECK((GB - first).cwiseAbs().maxCoeff() == 0.0);
      }
    }
    // no points: nothing written
    Eigen::MatrixXd none(0, d);
    evaluate(s.B, s.emb, std::vector<Eigen::Index>{}, none);
    BezierPoints kept = BezierPoints::Constant(s.B.rows(), d, 1.0);
    evaluate_transpose(s.emb, std::vector<Eigen::Index>{}, Eigen::MatrixXd(0, d), m, kept);
    CHECK(kept.isConstant(1.0));
  }
}

TEST_CASE("the subset evaluation and its transpose reject bad indices and sizes", "[evaluate][adjoint]") {
  const Setup s = make(3, 200);
  const int m = static_cast<int>(s.M.T.rows());
  Eigen::MatrixXd out(2, 3);
  CHECK_THROWS_WITH(evaluate(s.B, s.emb, std::vector<Eigen::Index>{0, 200}, out), Catch::Contains("points[1] = 200"));
  CHECK_THROWS_WITH(evaluate(s.B, s.emb, std::vector<Eigen::Index>{-1, 0}, out), Catch::Contains("points[0] = -1"));
  Eigen::MatrixXd small(1, 3);
  CHECK_THROWS_WITH(evaluate(s.B, s.emb, std::vector<Eigen::Index>{0, 1}, small), Catch::Contains("positions must be 2 x 3"));
  BezierPoints GB(s.B.rows(), 3);
  const Eigen::MatrixXd G = Eigen::MatrixXd::Ones(2, 3);
  CHECK_THROWS_WITH(evaluate_transpose(s.emb, std::vector<Eigen::Index>{0}, G, m, GB), Catch::Contains("must be 1 x 3"));
  CHECK_THROWS_WITH(evaluate_transpose(s.emb, std::vector<Eigen::Index>{5, 200}, G, m, GB), Catch::Contains("points[1] = 200"));
  Eigen::MatrixXd bad = G;
  bad(1, 2) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(evaluate_transpose(s.emb, std::vector<Eigen::Index>{5, 6}, bad, m, GB), Catch::Contains("row 1"));
}
