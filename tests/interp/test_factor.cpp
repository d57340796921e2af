// The internal sparse Cholesky factor (interp/src/linalg/factor.hpp) against Eigen's dense LLT, an
// independent solver: every width of right-hand sides, both factorizations, the serial sweeps and
// the sweeps split into groups of subtrees with the top part's supernodes shared out between the
// threads (the grouped schedule, forced on a small matrix), on 1 to 3 of the library's threads
// with the same result.
#include <catch2/catch.hpp>

#include "linalg/factor.hpp"

#include <mbi/interp/threads.hpp>

#include <Eigen/Dense>
#include <random>
#include <set>

using mbi::interp::detail::CholeskyFactor;

namespace {
// SPD: the 7-point Laplacian of an nx x ny x nz grid plus a jittered diagonal, 3 unknowns a node
// coupled by a random symmetric 3 x 3 block (like the modified-BI m-block's vertex blocks)
Eigen::SparseMatrix<double> grid_spd(int nx, int ny, int nz, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const int nn = nx * ny * nz, n = 3 * nn;
  auto id = [&](int x, int y, int z) { return (z * ny + y) * nx + x; };
  std::vector<Eigen::Triplet<double>> t;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        const int a = id(x, y, z);
        int deg = 0;
        const int nb[3][3] = {{x + 1, y, z}, {x, y + 1, z}, {x, y, z + 1}};
        for (const auto& q : nb) {
          if (q[0] >= nx || q[1] >= ny || q[2] >= nz) continue;
          const int b = id(q[0], q[1], q[2]);
          const double wgt = 0.5 + uni(rng);
          for (int c = 0; c < 3; ++c) {
            t.emplace_back(3 * a + c, 3 * b + c, -wgt);
            t.emplace_back(3 * b + c, 3 * a + c, -wgt);
            t.emplace_back(3 * a + c, 3 * a + c, wgt);
            t.emplace_back(3 * b + c, 3 * b + c, wgt);
          }
          ++deg;
        }
        const double o = 0.02 * uni(rng);  // |o| < half the smallest diagonal: SPD
        for (int c = 0; c < 3; ++c) {
          t.emplace_back(3 * a + c, 3 * a + c, 0.05 + uni(rng) * 0.1);
          t.emplace_back(3 * a + c, 3 * a + (c + 1) % 3, o);
          t.emplace_back(3 * a + (c + 1) % 3, 3 * a + c, o);
        }
        (void)deg;
      }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

double solve_error(const CholeskyFactor& F, const Eigen::LLT<Eigen::MatrixXd>& ref, int w, unsigned seed) {
  const int n = F.n;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> B(n, w);
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < w; ++c) B(i, c) = uni(rng);
  const Eigen::MatrixXd want = ref.solve(Eigen::MatrixXd(B));
  F.solve(B.data(), w);
  return (Eigen::MatrixXd(B) - want).cwiseAbs().maxCoeff() / want.cwiseAbs().maxCoeff();
}
}  // namespace

TEST_CASE("sparse Cholesky sweeps equal a dense LLT for 1 to 8 right-hand sides, serial and split into subtree groups", "[factorization]") {
  const Eigen::SparseMatrix<double> A = grid_spd(8, 8, 5, 91);  // 960 unknowns
  const Eigen::LLT<Eigen::MatrixXd> ref{Eigen::MatrixXd(A)};
  REQUIRE(ref.info() == Eigen::Success);
  std::vector<bool> which{false};
  if (mbi::interp::detail::cholmod_available()) which.push_back(true);
  for (bool cholmod : which) {
    CholeskyFactor F = mbi::interp::detail::cholesky(A, cholmod);
    CAPTURE(F.method);
    // supernodes of every width modulo the sweeps' panel of 8 (CHOLMOD's; Eigen's have one column)
    std::set<int> widths;
    for (size_t s = 0; s + 1 < F.super.size(); ++s) widths.insert((F.super[s + 1] - F.super[s]) % 8);
    CHECK(widths.size() == (cholmod ? 8u : 1u));
    for (int groups : {1, 2, 3}) {
      F.schedule(groups, 0);
      CAPTURE(groups);
      if (groups > 1) {
        // the split exists and covers every supernode once
        CHECK(F.bins == groups);
        size_t count = F.top.size();
        for (const auto& g : F.groups) {
          CHECK(!g.empty());
          count += g.size();
        }
        CHECK(count == F.super.size() - 1);
      }
      // top supernodes shared out between the threads from every size, and from the default
      for (std::ptrdiff_t split : {std::ptrdiff_t(0), std::ptrdiff_t(1) << 16}) {
        F.top_split = split;
        CAPTURE(split);
        for (int w = 1; w <= 8; ++w) {
          CAPTURE(w);
          CHECK(solve_error(F, ref, w, 100 + w) < 1e-12);
          // the same values on any number of threads
          Eigen::MatrixXd one;
          for (int threads : {1, 2, 3}) {
            mbi::interp::set_threads(threads);
            Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> X =
                Eigen::MatrixXd::Constant(A.rows(), w, 1.0) + Eigen::MatrixXd::Identity(A.rows(), w);
            F.solve(X.data(), w);
            if (threads == 1) one = X;
            else CHECK(Eigen::MatrixXd(X) == one);
          }
          mbi::interp::set_threads(0);
        }
      }
    }
  }
}

TEST_CASE("sparse Cholesky: a matrix that is not positive definite is refused", "[factorization]") {
  Eigen::SparseMatrix<double> A = grid_spd(3, 3, 3, 92);
  A.coeffRef(5, 5) = -1.0;
  CHECK_THROWS_WITH(mbi::interp::detail::cholesky(A, false), Catch::Contains("positive definite"));
  if (mbi::interp::detail::cholmod_available())
    CHECK_THROWS_WITH(mbi::interp::detail::cholesky(A, true), Catch::Contains("positive definite"));
}
