// The precompute's factorizations (Eigen SimplicialLLT, CHOLMOD supernodal) and the per-frame
// solve paths (sparse sweeps, dense operator) against each other: the same M to round-off.
#include <catch2/catch.hpp>

#include "test_support.hpp"

using namespace mbi::interp;
using namespace mbi::test;

namespace {
double rel(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1e-300, b.cwiseAbs().maxCoeff());
}

ModifiedBI make(const Mesh& M, Factorization f, SolvePath p, bool pin = false) {
  Options o;
  o.factorization = f;
  o.solve_path = p;
  o.pin_boundary = pin;
  return ModifiedBI(M.U, M.T, o);
}
}  // namespace

TEST_CASE("Eigen and CHOLMOD factorizations give the same M to round-off, on both solve paths", "[factorization]") {
  if (!cholmod_available()) {
    // this build has Eigen only: asking for CHOLMOD is an error that says so
    const Mesh M = jittered_mesh(3, 61);
    CHECK_THROWS_WITH(make(M, Factorization::Cholmod, SolvePath::Sparse), Catch::Contains("CHOLMOD"));
    CHECK(make(M, Factorization::Automatic, SolvePath::Sparse).factorization().find("Eigen") == 0);
    return;
  }
  for (int d : {2, 3}) {
    for (bool pin : {false, true}) {
      const Mesh M = jittered_mesh(d, 62);
      const Eigen::MatrixXd X = smooth_deform(M.U, 0.4);
      const ModifiedBI e = make(M, Factorization::Eigen, SolvePath::Sparse, pin);
      const ModifiedBI c = make(M, Factorization::Cholmod, SolvePath::Sparse, pin);
      const ModifiedBI cd = make(M, Factorization::Cholmod, SolvePath::Dense, pin);
      const ModifiedBI a = make(M, Factorization::Automatic, SolvePath::Automatic, pin);
      CHECK(e.factorization().find("Eigen") == 0);
      CHECK(c.factorization().find("CHOLMOD") == 0);
      CHECK(a.factorization().find("CHOLMOD") == 0);
      const Eigen::MatrixXd Me = e.solve(X);
      CHECK(rel(c.solve(X), Me) < 1e-10);
      CHECK(rel(cd.solve(X), Me) < 1e-10);
      CHECK(rel(a.solve(X), Me) < 1e-10);
      CHECK(c.factor_nonzeros() > 0);
      CHECK(c.memory_bytes() > 0);
      // Eigen's columns store exactly L; CHOLMOD's supernodes (a vertex's d columns at least)
      // also store their diagonal blocks' upper triangles
      CHECK(e.factor_stored_values() == e.factor_nonzeros());
      CHECK(c.factor_stored_values() > c.factor_nonzeros());
      CHECK(c.factor_index_bytes() >= 4LL * c.unknowns());  // each column is a row of its supernode
    }
  }
}

TEST_CASE("sparse solve on a 1,331-vertex box: both factorizations, dense positions within 1e-6 of the model size", "[factorization]") {
  const Mesh M = box_tet_mesh(10, 10, 10, Eigen::Vector3d(10, 10, 10));
  const Eigen::MatrixXd X = twist_bend(M.U, 1.2, 0.1);
  const double size = 10.0;
  std::vector<Factorization> fs{Factorization::Eigen};
  if (cholmod_available()) fs.push_back(Factorization::Cholmod);
  std::vector<Eigen::MatrixXd> Ms;
  for (Factorization f : fs) {
    const ModifiedBI s = make(M, f, SolvePath::Automatic);
    CHECK(!s.dense_operator());  // 3,987 x 1,331 entries: above the dense threshold
    Ms.push_back(s.solve(X));
    // M solves the reduced system: the energy's gradient in m vanishes on the free unknowns,
    // i.e. (alpha H_vibr + beta H_disc) m + beta H_mx x = 0 there (fact 1)
    for (int c = 0; c < 3; ++c) {
      const Eigen::VectorXd m = component(Ms.back(), 3, c);
      const Eigen::VectorXd g = s.alpha() * (s.vibr_hessian_mm() * m) + s.beta() * (s.disc_hessian_mm() * m) +
                                s.beta() * (s.disc_hessian_mx() * X.col(c));
      const double scale = (s.beta() * (s.disc_hessian_mx() * X.col(c))).cwiseAbs().maxCoeff();
      int pinned = 0;  // the gauge pins (6 here) carry a reaction; every other entry is zero
      for (Eigen::Index i = 0; i < g.size(); ++i)
        if (std::abs(g(i)) > 1e-9 * scale) ++pinned;
      CHECK(pinned <= 6);
    }
  }
  if (Ms.size() == 2) {
    CHECK(rel(Ms[1], Ms[0]) < 1e-9);
    // dense positions through both: within 1e-6 of the model size (they agree far better)
    std::mt19937 rng(63);
    std::uniform_real_distribution<double> uni(0.01, 9.99);
    Eigen::MatrixXd P(20000, 3);
    for (Eigen::Index i = 0; i < P.rows(); ++i) P.row(i) << uni(rng), uni(rng), uni(rng);
    const Embedding emb = embed(M.U, M.T, P);
    Eigen::MatrixXd p0, p1;
    evaluate<double>(bezier_points(M.U, M.T, X, Ms[0]), emb, p0);
    evaluate<double>(bezier_points(M.U, M.T, X, Ms[1]), emb, p1);
    CHECK((p1 - p0).cwiseAbs().maxCoeff() < 1e-6 * size);
  }
}
