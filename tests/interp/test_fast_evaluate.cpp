// The compact float kernel (FastEvaluator) against the double kernel (interp::evaluate<double>).
#include <catch2/catch.hpp>

#include "common/sanitizers.hpp"
#include "test_support.hpp"

#include <mbi/interp/threads.hpp>

#include <algorithm>
#include <cfloat>
#include <cstdint>
#include <cstring>

using namespace mbi::interp;
using namespace mbi::test;

namespace {
struct FastSetup {
  Mesh M;
  BezierPoints B, Bbi;
  Embedding emb;
  Eigen::MatrixXd normals;
};

FastSetup make_fast(int d, int points, double lo, double hi, Eigen::RowVectorXd offset = {}) {
  FastSetup s;
  s.M = jittered_mesh(d, 51);
  Eigen::MatrixXd X = smooth_deform(s.M.U, 0.5);
  const ModifiedBI mbi(s.M.U, s.M.T);
  s.B = mbi.bezier(X, mbi.solve(X));
  if (offset.size() == d) {  // the model far from the origin: float keeps relative accuracy
    X.rowwise() += offset;
    s.B = mbi.bezier(X, mbi.solve(X));
  }
  s.Bbi = bezier_bi(X, s.M.T);
  std::mt19937 rng(52);
  std::uniform_real_distribution<double> uni(lo, hi);
  Eigen::MatrixXd P(points, d);
  for (int i = 0; i < points; ++i)
    for (int c = 0; c < d; ++c) P(i, c) = uni(rng);
  s.emb = embed(s.M.U, s.M.T, P);
  s.normals = random_matrix(points, d, 53);
  s.normals.rowwise().normalize();
  return s;
}

// the first 64-byte boundary at or after p
float* align64(float* p) {
  return reinterpret_cast<float*>((reinterpret_cast<std::uintptr_t>(p) + 63) & ~std::uintptr_t(63));
}

// Float round-off bound for a position: 32 ulp of the largest control-point coordinate (the
// coefficients are differences of control points and b is in [0, 1] inside an element).
double position_tolerance(const BezierPoints& B) { return 32 * FLT_EPSILON * B.cwiseAbs().maxCoeff(); }

// Every kernel this CPU runs, the widest first: each test below runs on all of them. Point counts
// of the form 16 k + 13 (and thread blocks of 32,768) leave, after the AVX-512 normals kernel's
// groups of 16, three groups of 4 and a 1-point tail, so each test runs every path of it.
std::vector<Simd> kernels() {
  std::vector<Simd> k;
  for (Simd v : {Simd::Avx512, Simd::Avx2, Simd::Portable})
    if (FastEvaluator::supported(v)) k.push_back(v);
  return k;
}
}  // namespace

TEST_CASE("FastEvaluator: the kernels this CPU runs, and which one Auto picks", "[fast_evaluate]") {
  const FastSetup s3 = make_fast(3, 10, 0.0, 1.0), s2 = make_fast(2, 10, 0.0, 1.0);
  const std::vector<Simd> k = kernels();
  REQUIRE(k.back() == Simd::Portable);
  CHECK(FastEvaluator::supported(Simd::Auto));
  WARN("kernels on this CPU: " << [&] {
    std::string names;
    for (Simd v : k) names += std::string(names.empty() ? "" : ", ") + FastEvaluator::name(v);
    return names;
  }());
  CHECK(FastEvaluator(s3.emb).simd() == k.front());  // Auto: the widest
  for (Simd v : k) CHECK(FastEvaluator(s3.emb, 0, v).simd() == v);
  CHECK(FastEvaluator(s2.emb).simd() == Simd::Portable);  // 2D: the portable loop
  CHECK(std::string(FastEvaluator::name(Simd::Avx512)) == "avx512");
  CHECK(std::string(FastEvaluator::name(Simd::Portable)) == "portable");
  for (Simd v : {Simd::Avx512, Simd::Avx2})
    if (!FastEvaluator::supported(v))
      CHECK_THROWS_WITH(FastEvaluator(s3.emb, 0, v), Catch::Contains(FastEvaluator::name(v)));
}

// The two x86 kernels sum every position in the same order with the same fused multiply-adds,
// so they agree exactly (compared with ==, which takes -0 == +0); their normals differ in the
// last bits (other formulas for cof(D) m), each within 2e-5 of the double kernel's.
TEST_CASE("FastEvaluator: the AVX-512 and AVX2 kernels give the same positions", "[fast_evaluate]") {
  if (!FastEvaluator::supported(Simd::Avx512)) {
    WARN("skipped: this CPU has no AVX-512");
    return;
  }
  const FastSetup s = make_fast(3, mbi::test::sized(100013), -0.2, 1.2);
  for (const BezierPoints* B : {&s.B, &s.Bbi}) {
    RowMatrixXf p[2], n[2], q[2];
    int i = 0;
    for (Simd v : {Simd::Avx512, Simd::Avx2}) {
      FastEvaluator fe(s.emb, 0, v);
      fe.set_rest_normals(s.normals);
      fe.evaluate(*B, p[i], n[i]);
      fe.evaluate(*B, q[i]);
      ++i;
    }
    CHECK((p[0].array() == p[1].array()).all());
    CHECK((q[0].array() == q[1].array()).all());
    CHECK((n[0] - n[1]).cwiseAbs().maxCoeff() < 4e-5f);
  }
}

TEST_CASE("FastEvaluator: float positions and normals agree with the double kernel to float round-off", "[fast_evaluate]") {
  for (int d : {2, 3}) {
    for (bool far : {false, true}) {
      const Eigen::RowVectorXd offset = far ? Eigen::RowVectorXd::Constant(d, 1000.0) : Eigen::RowVectorXd();
      // points inside and outside (extrapolated) the control mesh
      const FastSetup s = make_fast(d, mbi::test::sized(50013), -0.2, 1.2, offset);
      REQUIRE(!s.emb.outside.empty());
      for (const BezierPoints* B : {&s.B, &s.Bbi}) for (Simd v : kernels()) {
        INFO("d = " << d << ", far " << far << ", kernel " << FastEvaluator::name(v));
        Eigen::MatrixXd pd, nd;
        evaluate<double>(*B, s.emb, s.normals, pd, nd, 1);
        FastEvaluator fe(s.emb, 0, v);
        fe.set_rest_normals(s.normals);
        RowMatrixXf pf, nf;
        fe.evaluate(*B, pf, nf);
        REQUIRE(pf.rows() == pd.rows());
        REQUIRE(pf.cols() == d);
        const double tol = position_tolerance(*B);
        CHECK((pf.cast<double>() - pd).cwiseAbs().maxCoeff() <= tol);
        // unit normals: float accuracy of a normalised cof(J) n, away from singular J
        double nerr = 0;
        for (Eigen::Index i = 0; i < nd.rows(); ++i)
          nerr = std::max(nerr, (nf.row(i).cast<double>() - nd.row(i)).norm());
        CHECK(nerr < 2e-5);
        // positions alone: the same values
        RowMatrixXf p2;
        fe.evaluate(*B, p2);
        CHECK((p2 - pf).cwiseAbs().maxCoeff() == 0.0f);
      }
    }
  }
}

TEST_CASE("FastEvaluator: thread counts, caller memory and repeated calls give identical results", "[fast_evaluate]") {
  const FastSetup s = make_fast(3, 200013, 0.0, 1.0);
  for (Simd v : kernels()) {
  INFO("kernel " << FastEvaluator::name(v));
  FastEvaluator ref(s.emb, 1, v);
  ref.set_rest_normals(s.normals);
  RowMatrixXf p1, n1;
  ref.evaluate(s.B, p1, n1);
  for (int threads : {2, 3, 7}) {
    FastEvaluator fe(s.emb, threads, v);
    fe.set_rest_normals(s.normals);
    RowMatrixXf p, n;
    fe.evaluate(s.B, p, n);
    CHECK((p - p1).cwiseAbs().maxCoeff() == 0.0f);
    CHECK((n - n1).cwiseAbs().maxCoeff() == 0.0f);
    // the same matrices again: no reallocation
    const float* data = p.data();
    fe.evaluate(s.B, p, n);
    CHECK(p.data() == data);
    // unaligned caller memory (offset by one float): plain stores, same values
    std::vector<float> buf(3 * p1.rows() + 1), nbuf(3 * p1.rows() + 1);
    fe.evaluate(s.B, buf.data() + 1, nbuf.data() + 1);
    const Eigen::Map<const RowMatrixXf> pm(buf.data() + 1, p1.rows(), 3), nm(nbuf.data() + 1, p1.rows(), 3);
    CHECK((pm - p1).cwiseAbs().maxCoeff() == 0.0f);
    CHECK((nm - n1).cwiseAbs().maxCoeff() == 0.0f);
    // positions alone (the other kernel and layout), aligned and not: the same positions
    RowMatrixXf p0;
    fe.evaluate(s.B, p0);
    CHECK((p0 - p1).cwiseAbs().maxCoeff() == 0.0f);
    std::fill(buf.begin(), buf.end(), -1e30f);
    fe.evaluate(s.B, buf.data() + 1, nullptr);
    CHECK((pm - p1).cwiseAbs().maxCoeff() == 0.0f);
  }
  }
  FastEvaluator ref(s.emb, 1);
  CHECK(ref.bytes_per_point(false) == 28);
  CHECK(ref.bytes_per_point(true) == 52);
}

// The vector kernels write 16-byte streaming stores where both outputs are 16-byte aligned and
// plain stores otherwise, in groups of 4 points, each thread its blocks, with the last points of
// a range copied one by one from a group of 4: at every offset from a 64-byte boundary the same values come out,
// and nothing before or after the outputs changes.
TEST_CASE("FastEvaluator: outputs at every offset within a cache line, nothing written outside them", "[fast_evaluate]") {
  const FastSetup s = make_fast(3, 70013, 0.0, 1.0);  // 3 blocks, the last one partial, then a tail
  const long long n = 3 * 70013;
  for (Simd v : kernels()) {
    FastEvaluator ref(s.emb, 1, v);
    ref.set_rest_normals(s.normals);
    RowMatrixXf p1, n1;
    ref.evaluate(s.B, p1, n1);
    const Eigen::Map<const Eigen::VectorXf> pv(p1.data(), n), nv(n1.data(), n);
    for (int threads : {1, 2, 3}) {
      FastEvaluator fe(s.emb, threads, v);
      fe.set_rest_normals(s.normals);
      std::vector<float> pbuf(n + 64, -7.0f), nbuf(n + 64, -7.0f);
      for (int off = 0; off < 16; ++off) {
        INFO("kernel " << FastEvaluator::name(v) << ", threads " << threads << ", offset " << off << " floats");
        float* pos = align64(pbuf.data()) + off;
        float* nor = align64(nbuf.data()) + (off + 4) % 16;  // another offset, 16-byte aligned when pos is
        // buf holds out's n floats and -7 everywhere else
        auto only = [n](const std::vector<float>& buf, const float* out) {
          for (const float* f = buf.data(); f < buf.data() + buf.size(); ++f)
            if (f < out || f >= out + n) REQUIRE(*f == -7.0f);
        };
        fe.evaluate(s.B, pos, nor);
        CHECK((Eigen::Map<const Eigen::VectorXf>(pos, n) - pv).cwiseAbs().maxCoeff() == 0.0f);
        CHECK((Eigen::Map<const Eigen::VectorXf>(nor, n) - nv).cwiseAbs().maxCoeff() == 0.0f);
        only(pbuf, pos);
        only(nbuf, nor);
        std::fill(pbuf.begin(), pbuf.end(), -7.0f);
        fe.evaluate(s.B, pos, nullptr);  // positions alone: the other kernel
        CHECK((Eigen::Map<const Eigen::VectorXf>(pos, n) - pv).cwiseAbs().maxCoeff() == 0.0f);
        only(pbuf, pos);
        std::fill(pbuf.begin(), pbuf.end(), -7.0f);
        std::fill(nbuf.begin(), nbuf.end(), -7.0f);
      }
    }
  }
}

// The vector kernels take groups of 4 points; with normals the AVX2 kernel finishes each group
// two groups later (positions, then cof(D) m, then the renormalisation), the AVX-512 kernel takes
// groups of 16 with the normals of each finished during the next, then groups of 4: 1-4 groups
// of 4, 1-4 groups of 16 with 0-3 groups of 4 after them, and tails of 1-3 points.
TEST_CASE("FastEvaluator: few points (tails shorter than a group of 4, the first groups) and an empty embedding", "[fast_evaluate]") {
  for (int p : {1, 2, 3, 4, 5, 7, 8, 9, 11, 12, 13, 15, 16, 17, 19, 20, 28, 31, 32, 33, 35, 47, 48, 51, 64, 67, 79, 100})
  for (Simd v : kernels()) {
    INFO("points " << p << ", kernel " << FastEvaluator::name(v));
    const FastSetup s = make_fast(3, p, 0.0, 1.0);
    Eigen::MatrixXd pd, nd;
    evaluate<double>(s.B, s.emb, s.normals, pd, nd, 1);
    FastEvaluator fe(s.emb, 0, v);
    fe.set_rest_normals(s.normals);
    RowMatrixXf pf, nf;
    fe.evaluate(s.B, pf, nf);
    CHECK((pf.cast<double>() - pd).cwiseAbs().maxCoeff() <= position_tolerance(s.B));
    CHECK((nf.cast<double>() - nd).cwiseAbs().maxCoeff() < 2e-5);
    RowMatrixXf p0;
    fe.evaluate(s.B, p0);
    CHECK((p0 - pf).cwiseAbs().maxCoeff() == 0.0f);
  }
  Embedding empty;
  empty.bary.resize(0, 4);
  FastEvaluator fe(empty);
  RowMatrixXf pf;
  const FastSetup s = make_fast(3, 1, 0.0, 1.0);
  fe.evaluate(s.B, pf);
  CHECK(pf.rows() == 0);
}

// Points in a mesh's order (most follow a point of the same element) take the kernel without
// prefetches: the same results as the double kernel.
TEST_CASE("FastEvaluator: points stored by element agree with the double kernel", "[fast_evaluate]") {
  const FastSetup s = make_fast(3, 70013, 0.0, 1.0);  // 2 threads take at least 2 x 32K points
  CHECK_FALSE(FastEvaluator(s.emb).coherent());  // random order: the prefetching kernel
  std::vector<int> order(static_cast<size_t>(s.emb.size()));
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return s.emb.element(a) < s.emb.element(b); });
  Embedding sorted = s.emb;
  Eigen::MatrixXd normals(s.normals.rows(), 3);
  for (size_t i = 0; i < order.size(); ++i) {
    sorted.element(static_cast<Eigen::Index>(i)) = s.emb.element(order[i]);
    sorted.bary.row(static_cast<Eigen::Index>(i)) = s.emb.bary.row(order[i]);
    normals.row(static_cast<Eigen::Index>(i)) = s.normals.row(order[i]);
  }
  sorted.outside.clear();
  Eigen::MatrixXd pd, nd;
  evaluate<double>(s.B, sorted, normals, pd, nd, 1);
  for (int threads : {1, 2}) for (Simd v : kernels()) {
    INFO("threads " << threads << ", kernel " << FastEvaluator::name(v));
    FastEvaluator fe(sorted, threads, v);
    REQUIRE(fe.coherent());
    REQUIRE(fe.threads() == (mbi::interp::threads_available() ? threads : 1));  // a serial build: 1
    fe.set_rest_normals(normals);
    // positions alone first (the pairs layout), then with normals (the packed layout, but for the
    // AVX-512 kernel), then alone again: the layout may change between calls, the positions do not
    RowMatrixXf p0, pf, nf, p2;
    fe.evaluate(s.B, p0);
    fe.evaluate(s.B, pf, nf);
    fe.evaluate(s.B, p2);
    CHECK((pf.cast<double>() - pd).cwiseAbs().maxCoeff() <= position_tolerance(s.B));
    CHECK((nf.cast<double>() - nd).cwiseAbs().maxCoeff() < 2e-5);
    CHECK((p0 - pf).cwiseAbs().maxCoeff() == 0.0f);
    CHECK((p2 - pf).cwiseAbs().maxCoeff() == 0.0f);
  }
}

// Normals are cof(D) (cof(A)^T n) with D = dx/db quadratic in the model's size: the kernel
// rescales by powers of 2 so that models of any size float holds keep their normals.
TEST_CASE("FastEvaluator: normals at extreme model scales, and zero on a collapsed element", "[fast_evaluate]") {
  for (int d : {2, 3}) {
    const FastSetup s = make_fast(d, 4013, -0.1, 1.1);
    Eigen::MatrixXd pd, nd;
    evaluate<double>(s.B, s.emb, s.normals, pd, nd, 1);
    // the same points stored by element (the kernels without prefetches)
    std::vector<int> order(static_cast<size_t>(s.emb.size()));
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return s.emb.element(a) < s.emb.element(b); });
    Embedding sorted = s.emb;
    Eigen::MatrixXd snormals = s.normals, spd = pd, snd = nd;
    for (size_t i = 0; i < order.size(); ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      sorted.element(r) = s.emb.element(order[i]);
      sorted.bary.row(r) = s.emb.bary.row(order[i]);
      snormals.row(r) = s.normals.row(order[i]);
      spd.row(r) = pd.row(order[i]);
      snd.row(r) = nd.row(order[i]);
    }
    sorted.outside.clear();
    for (double scale : {1e-30, 1e-20, 1e-12, 1e12, 1e20, 1e30}) for (Simd v : kernels()) for (bool by_element : {false, true}) {
      // the same model scaled: Bezier points times scale, gradients over the rest space divided
      Embedding emb = by_element ? sorted : s.emb;
      emb.gradients /= scale;
      const BezierPoints B = s.B * scale;
      FastEvaluator fe(emb, 1, v);
      REQUIRE(fe.coherent() == by_element);
      fe.set_rest_normals(by_element ? snormals : s.normals);
      RowMatrixXf pf, nf;
      fe.evaluate(B, pf, nf);
      INFO("d = " << d << ", scale " << scale << ", kernel " << FastEvaluator::name(v) << ", by element " << by_element);
      CHECK(((pf.cast<double>() / scale) - (by_element ? spd : pd)).cwiseAbs().maxCoeff() <= position_tolerance(s.B));
      CHECK((nf.cast<double>() - (by_element ? snd : nd)).cwiseAbs().maxCoeff() < 2e-5);
    }
    // element of point 0 collapsed to one point: every coefficient is exactly 0, so J = 0 and the
    // normal is 0 (the double kernel's J is round-off there, from the Bernstein derivatives)
    BezierPoints B = s.B;
    const int K = (d + 1) * (d + 2) / 2;
    const int e = s.emb.element(0);
    for (int k = 0; k < K; ++k) B.row(e * K + k) = s.B.row(e * K);
    for (Simd v : kernels()) {
      INFO("d = " << d << ", kernel " << FastEvaluator::name(v));
      FastEvaluator fe(s.emb, 1, v);
      fe.set_rest_normals(s.normals);
      RowMatrixXf pf, nf;
      fe.evaluate(B, pf, nf);
      int collapsed = 0;
      for (Eigen::Index i = 0; i < nf.rows(); ++i) {
        if (s.emb.element(i) != e) continue;
        ++collapsed;
        CHECK(nf.row(i).norm() == 0.0f);
      }
      CHECK(collapsed > 0);
      CHECK(std::isfinite(nf.cast<double>().sum()));
    }
  }
}

TEST_CASE("FastEvaluator rejects inconsistent input", "[fast_evaluate]") {
  const FastSetup s = make_fast(3, 100, 0.0, 1.0);
  FastEvaluator fe(s.emb);
  RowMatrixXf p, n;
  CHECK_THROWS_WITH(fe.evaluate(s.B.topRows(s.B.rows() - 10), p), Catch::Contains("Bezier points"));
  CHECK_THROWS_WITH(fe.evaluate(s.B, p, n), Catch::Contains("no rest normals"));
  CHECK_THROWS_WITH(fe.set_rest_normals(s.normals.topRows(10)), Catch::Contains("rest normals"));
  Embedding nograd = s.emb;
  nograd.gradients.resize(0, 0);
  FastEvaluator fg(nograd);
  CHECK_THROWS_WITH(fg.set_rest_normals(s.normals), Catch::Contains("gradients"));
  Embedding bad = s.emb;
  bad.element(3) = -1;
  CHECK_THROWS_WITH(FastEvaluator(bad), Catch::StartsWith("point 3"));
  CHECK_THROWS_AS(FastEvaluator(s.emb, -1), mbi::Error);
}

// Points in random order over element terms larger than a cache: the evaluator sorts its records
// by element and scatters each result to its point's row. Every row is then the same bits as
// with the points stored by element (no permutation), on every kernel, 1 and 2 threads,
// positions alone and with normals, and as each point evaluated alone (the last points of a
// range run as a whole group, as the others).
TEST_CASE("FastEvaluator: points in random order over a large mesh give each point's row, bit for bit", "[fast_evaluate]") {
  const Mesh M = box_tet_mesh(30, 30, 30);  // 162,000 tetrahedra: 20.7 MB of element terms
  const BezierPoints B = bezier_bi(smooth_deform(M.U, 0.5), M.T);
  const int p = mbi::test::sized(100013);
  const Embedding emb = embed(M.U, M.T, random_matrix(p, 3, 61).array() * 0.55 + 0.5);  // some outside
  Eigen::MatrixXd normals = random_matrix(p, 3, 62);
  normals.rowwise().normalize();
  std::vector<int> order(static_cast<size_t>(p));
  for (int i = 0; i < p; ++i) order[static_cast<size_t>(i)] = i;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return emb.element(a) < emb.element(b); });
  Embedding sorted = emb;
  Eigen::MatrixXd snormals = normals;
  for (int k = 0; k < p; ++k) {
    sorted.element(k) = emb.element(order[static_cast<size_t>(k)]);
    sorted.bary.row(k) = emb.bary.row(order[static_cast<size_t>(k)]);
    snormals.row(k) = normals.row(order[static_cast<size_t>(k)]);
  }
  auto same_bits = [](const RowMatrixXf& a, Eigen::Index i, const RowMatrixXf& b, Eigen::Index k) {
    return std::memcmp(a.row(i).data(), b.row(k).data(), 3 * sizeof(float)) == 0;
  };
  Eigen::MatrixXd pd, nd;
  evaluate<double>(B, emb, normals, pd, nd, 1);
  for (Simd v : kernels()) for (int threads : {1, 2}) {
    INFO("kernel " << FastEvaluator::name(v) << ", threads " << threads);
    FastEvaluator fr(emb, threads, v), fs(sorted, threads, v);
    REQUIRE(fr.sorted_by_element());
    REQUIRE_FALSE(fs.sorted_by_element());  // sorted already: no permutation
    CHECK(fr.coherent() == fs.coherent());
    fr.set_rest_normals(normals);
    fs.set_rest_normals(snormals);
    RowMatrixXf pr, nr, qr, ps, ns, qs;
    fr.evaluate(B, pr, nr);
    fr.evaluate(B, qr);
    fs.evaluate(B, ps, ns);
    fs.evaluate(B, qs);
    CHECK((pr.cast<double>() - pd).cwiseAbs().maxCoeff() <= position_tolerance(B));
    CHECK((nr.cast<double>() - nd).cwiseAbs().maxCoeff() < 2e-5);
    int differ = 0;
    for (int k = 0; k < p; ++k) {
      const int i = order[static_cast<size_t>(k)];
      differ += !same_bits(pr, i, ps, k) || !same_bits(nr, i, ns, k) || !same_bits(qr, i, qs, k) || !same_bits(qr, i, pr, i);
    }
    CHECK(differ == 0);
    if (threads == 2) continue;
    for (int i = 0; i < p; i += p / 23 + 1) {  // points alone: a group of 4 of one real record
      Embedding one;
      one.element = emb.element.segment(i, 1);
      one.bary = emb.bary.row(i);
      one.gradients = emb.gradients;
      FastEvaluator fe(one, 1, v);
      fe.set_rest_normals(normals.row(i));
      RowMatrixXf p1, n1;
      fe.evaluate(B, p1, n1);
      CHECK(same_bits(p1, 0, pr, i));
      CHECK(same_bits(n1, 0, nr, i));
    }
  }
  // element terms that fit a cache: the points' own order
  CHECK_FALSE(FastEvaluator(make_fast(3, 1000, 0.0, 1.0).emb).sorted_by_element());
}

// Records in element order (stored so, or sorted by the evaluator over a large mesh) take the
// fused pass: each block of elements' terms computed just before its records, in a buffer of the
// thread. It gives the bits of the pass over the whole table, on every kernel, 1 and 2 threads,
// with points denser than the elements and sparser (groups of 4 that span more elements than a
// block holds, run one group at a time).
TEST_CASE("FastEvaluator: the fused pass gives the bits of the table's pass", "[fast_evaluate]") {
  const Mesh M = box_tet_mesh(30, 30, 30);  // 162,000 tetrahedra: 20.7 MB of element terms
  const BezierPoints B = bezier_bi(smooth_deform(M.U, 0.5), M.T);
  auto by_element = [](const Embedding& e) {
    std::vector<int> order(static_cast<size_t>(e.size()));
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return e.element(a) < e.element(b); });
    Embedding s = e;
    for (size_t i = 0; i < order.size(); ++i) {
      s.element(static_cast<Eigen::Index>(i)) = e.element(order[i]);
      s.bary.row(static_cast<Eigen::Index>(i)) = e.bary.row(order[i]);
    }
    s.outside.clear();
    return s;
  };
  auto compare = [&](const Embedding& emb, const BezierPoints& Bz, Simd v, int threads) {
    FastEvaluator fe(emb, threads, v);
    REQUIRE(fe.fused_terms());
    RowMatrixXf fused, table;
    fe.evaluate(Bz, fused);
    fe.set_fused_terms(false);
    REQUIRE_FALSE(fe.fused_terms());
    fe.evaluate(Bz, table);
    CHECK(std::memcmp(fused.data(), table.data(), static_cast<size_t>(fused.size()) * sizeof(float)) == 0);
    fe.set_fused_terms(true);
    fe.evaluate(Bz, table);  // after a table pass (another layout on some kernels): the same
    CHECK(std::memcmp(fused.data(), table.data(), static_cast<size_t>(fused.size()) * sizeof(float)) == 0);
  };
  for (int p : {mbi::test::sized(100013), 1013, 113, 3}) {
    const Embedding emb = embed(M.U, M.T, random_matrix(p, 3, 63).array() * 0.55 + 0.5);  // some outside
    const Embedding sorted = by_element(emb);
    for (Simd v : kernels()) for (int threads : {1, 2}) {
      INFO("points " << p << ", kernel " << FastEvaluator::name(v) << ", threads " << threads);
      if (p > 3) REQUIRE(FastEvaluator(emb, threads, v).sorted_by_element());
      compare(emb, B, v, threads);
      compare(sorted, B, v, threads);
    }
  }
  // 2D (the portable loop) over a small mesh: fused when stored by element, the table's pass
  // otherwise
  const FastSetup s = make_fast(2, 4013, 0.0, 1.0);
  CHECK_FALSE(FastEvaluator(s.emb).fused_terms());
  for (int threads : {1, 2}) compare(by_element(s.emb), s.B, Simd::Portable, threads);
}
