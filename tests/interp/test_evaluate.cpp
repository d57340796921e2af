// Evaluation kernel: float vs double, threads, BI, outside points, errors.
#include <catch2/catch.hpp>

#include "test_support.hpp"

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
