// Modified-BI: every fact of design/method.md as a property test, in 2D and 3D.
#include <catch2/catch.hpp>

#include "test_support.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace mbi::interp;
using namespace mbi::test;

namespace {
double rel(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(1e-300, b.norm());
}

// Quadratic form value [m; x]^T [Hmm Hmx; Hmx^T Hxx] [m; x].
double form(const Eigen::SparseMatrix<double>& Hmm, const Eigen::SparseMatrix<double>* Hmx,
            const Eigen::SparseMatrix<double>* Hxx, const Eigen::VectorXd& m, const Eigen::VectorXd& x) {
  const Eigen::VectorXd Hm = Hmm * m;
  double v = m.dot(Hm);
  if (Hmx) {
    const Eigen::VectorXd Hx = *Hmx * x;
    v += 2 * m.dot(Hx);
  }
  if (Hxx) {
    const Eigen::VectorXd Hxxx = *Hxx * x;
    v += x.dot(Hxxx);
  }
  return v;
}

// Field value at rest point u of element e (defining formula).
Eigen::MatrixXd sample_field(const Mesh& M, const Eigen::MatrixXd& X, const VertexMatrices& Mm,
                             int samples, unsigned seed) {
  const int d = static_cast<int>(M.U.cols());
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(M.T.rows()) - 1);
  Eigen::MatrixXd out(samples, d);
  for (int s = 0; s < samples; ++s) {
    const int e = pick(rng);
    const Eigen::VectorXd u = point_of(M.U, M.T, e, random_bary(d, rng));
    out.row(s) = evaluate_reference(M.U, M.T, X, Mm, e, u).transpose();
  }
  return out;
}
}  // namespace

// Also on meshes of more than 1,024 elements and interior faces: the assembly computes local
// Hessians a block of 1,024 at a time, so these take several blocks.
TEST_CASE("fact 1-2: per-component forms equal the energies for random M and X", "[modified_bi]") {
  for (int d : {2, 3}) {
    for (bool large : {false, true}) {
      Mesh M = jittered_mesh(d, 4);
      if (large) {
        M = d == 3 ? box_tet_mesh(8, 7, 6) : square_tri_mesh(40, 30);  // 2,016 tets / 2,400 triangles
        jitter(M, 0.2, d == 3 ? 1.0 / 8 : 1.0 / 40, 5);
        REQUIRE(interior_faces(M.T).rows() > 2048);
      }
      CAPTURE(d, large);
      const ModifiedBI mbi(M.U, M.T);
      const int n = static_cast<int>(M.U.rows());
      const VertexMatrices Mm = random_matrix(n * d, d, 21);  // rows differ per component
      const Eigen::MatrixXd X = smooth_deform(M.U) + 0.05 * random_matrix(n, d, 22);
      // Energies evaluated directly on the d x d matrices M_i (the paper's full d*d*n unknowns)
      const double ev = vibration_energy(M.U, M.T, Mm);
      const double ed = face_discontinuity(M.U, M.T, X, Mm).sum();
      const Eigen::SparseMatrix<double> vibr_mm = mbi.vibr_hessian_mm(), disc_mm = mbi.disc_hessian_mm();
      const Eigen::SparseMatrix<double> disc_mx = mbi.disc_hessian_mx(), disc_xx = mbi.disc_hessian_xx();
      double fv = 0, fd = 0;
      for (int c = 0; c < d; ++c) {
        const Eigen::VectorXd m = component(Mm, d, c);
        const Eigen::VectorXd x = X.col(c);
        fv += form(vibr_mm, nullptr, nullptr, m, x);
        fd += form(disc_mm, &disc_mx, &disc_xx, m, x);
      }
      CHECK(fv == Approx(ev).epsilon(1e-10));
      CHECK(fd == Approx(ed).epsilon(1e-10));
      CHECK(vibr_mm.rows() == d * n);  // d n, not d*d*n
      CHECK(disc_mx.cols() == n);
    }
  }
}

TEST_CASE("fact 2: E_vibr equals sum |t| ||Hess x||^2 from the field and does not depend on X", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh M = jittered_mesh(d, 5);
    const int n = static_cast<int>(M.U.rows());
    const VertexMatrices Mm = random_matrix(n * d, d, 31);
    const Eigen::MatrixXd X1 = smooth_deform(M.U), X2 = random_matrix(n, d, 32);
    // Hessian of x(u) inside each element by central differences (exact for a quadratic
    // up to round-off; h = 1e-3, tolerance 1e-6 relative).
    auto field_energy = [&](const Eigen::MatrixXd& X) {
      double E = 0;
      const double h = 1e-3;
      for (int e = 0; e < M.T.rows(); ++e) {
        Eigen::VectorXd u0 = Eigen::VectorXd::Zero(d);
        for (int k = 0; k <= d; ++k) u0 += M.U.row(M.T(e, k)).transpose() / (d + 1);
        const double vol = std::abs(element_volume(M.U, M.T, e));
        for (int c = 0; c < d; ++c) {
          Eigen::MatrixXd H(d, d);
          for (int p = 0; p < d; ++p)
            for (int q = 0; q < d; ++q) {
              auto f = [&](double sp, double sq) {
                Eigen::VectorXd u = u0;
                u(p) += sp * h;
                u(q) += sq * h;
                return evaluate_reference(M.U, M.T, X, Mm, e, u)(c);
              };
              H(p, q) = (f(1, 1) - f(1, -1) - f(-1, 1) + f(-1, -1)) / (4 * h * h);
            }
          E += vol * H.squaredNorm();
        }
      }
      return E;
    };
    const double ev = vibration_energy(M.U, M.T, Mm);
    CHECK(field_energy(X1) == Approx(ev).epsilon(1e-6));
    CHECK(field_energy(X2) == Approx(ev).epsilon(1e-6));
  }
}

TEST_CASE("fact 3: exact face integrals agree with quadrature of the Bezier gradients", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh M = jittered_mesh(d, 6);
    const int n = static_cast<int>(M.U.rows());
    const VertexMatrices Mm = random_matrix(n * d, d, 41);
    const Eigen::MatrixXd X = smooth_deform(M.U);
    const BezierPoints B = bezier_points(M.U, M.T, X, Mm);
    const Eigen::MatrixXi F = interior_faces(M.T);
    const Eigen::VectorXd E = face_discontinuity(M.U, M.T, X, Mm);
    // Quadrature exact for quadratics on the face: 2D Simpson on the segment, 3D edge-midpoint
    // rule on the triangle. The gradient jump is computed from jacobian() on each side.
    std::vector<std::pair<Eigen::VectorXd, double>> rule;  // face-barycentric point, weight
    if (d == 2) {
      rule = {{Eigen::Vector2d(1, 0), 1.0 / 6}, {Eigen::Vector2d(0.5, 0.5), 4.0 / 6}, {Eigen::Vector2d(0, 1), 1.0 / 6}};
    } else {
      rule = {{Eigen::Vector3d(0.5, 0.5, 0), 1.0 / 3}, {Eigen::Vector3d(0, 0.5, 0.5), 1.0 / 3},
              {Eigen::Vector3d(0.5, 0, 0.5), 1.0 / 3}};
    }
    double max_rel = 0;
    for (int f = 0; f < F.rows(); ++f) {
      double area;
      if (d == 2) {
        area = (M.U.row(F(f, 1)) - M.U.row(F(f, 0))).norm();
      } else {
        const Eigen::Vector3d a = (M.U.row(F(f, 1)) - M.U.row(F(f, 0))).transpose();
        const Eigen::Vector3d b = (M.U.row(F(f, 2)) - M.U.row(F(f, 0))).transpose();
        area = 0.5 * a.cross(b).norm();
      }
      double q = 0;
      for (const auto& [fb, w] : rule) {
        Eigen::VectorXd u = Eigen::VectorXd::Zero(d);
        for (int j = 0; j < d; ++j) u += fb(j) * M.U.row(F(f, j)).transpose();
        Eigen::MatrixXd J[2];
        for (int s = 0; s < 2; ++s) {
          const int e = F(f, d + s);
          const Eigen::MatrixXd A = basis_gradients(M.U, M.T, e);
          Eigen::VectorXd b(d + 1);
          b.tail(d) = A.bottomRows(d) * (u - M.U.row(M.T(e, 0)).transpose());
          b(0) = 1 - b.tail(d).sum();
          J[s] = jacobian(M.U, M.T, B, e, b);
        }
        q += w * area * (J[0] - J[1]).squaredNorm();
      }
      max_rel = std::max(max_rel, std::abs(q - E(f)) / std::max(1e-14, E(f)));
    }
    CHECK(max_rel < 1e-9);
    // x(u) is continuous across faces for any M: the jump is normal to the face, so the
    // tangential derivative along an interior edge agrees (checked at face midpoints).
  }
}

TEST_CASE("fact 4: null space of H_mm has dimension d + d(d-1)/2, pinning vertex 0 is not enough", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh M = jittered_mesh(d, 7);
    const ModifiedBI mbi(M.U, M.T);
    const Eigen::MatrixXd H =
        Eigen::MatrixXd(mbi.alpha() * mbi.vibr_hessian_mm() + mbi.beta() * mbi.disc_hessian_mm());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
    const Eigen::VectorXd ev = es.eigenvalues();
    const double tol = 1e-9 * ev.maxCoeff();  // null eigenvalues are round-off (~1e-15 max)
    int nulls = 0;
    for (int i = 0; i < ev.size(); ++i) nulls += ev(i) < tol;
    const int expected = d + d * (d - 1) / 2;
    CHECK(nulls == expected);
    CHECK(ev(expected) > 1e-6 * ev.maxCoeff());  // clear gap to the first non-null eigenvalue
    CHECK(mbi.null_space_dim() == expected);
    std::printf("null space dimension (d = %d): %d (smallest non-null eigenvalue / largest = %.3g)\n", d,
                nulls, ev(expected) / ev.maxCoeff());
    // The paper's fix (M_0 = 0) removes the d unknowns of component c at vertex 0 only.
    const Eigen::Index N = H.rows();
    const Eigen::MatrixXd Hr = H.bottomRightCorner(N - d, N - d);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> er(Hr);
    int nulls_r = 0;
    for (int i = 0; i < er.eigenvalues().size(); ++i) nulls_r += er.eigenvalues()(i) < tol;
    CHECK(nulls_r == expected - d);  // still singular (skew modes left)
    CHECK(nulls_r > 0);
    // The gauge vectors t + S u_i are in the null space.
    const int n = static_cast<int>(M.U.rows());
    Eigen::VectorXd g(d * n);
    const Eigen::MatrixXd S0 = random_matrix(d, d, 3);
    const Eigen::MatrixXd S = S0 - S0.transpose();
    const Eigen::VectorXd t = random_matrix(d, 1, 4);
    for (int i = 0; i < n; ++i) g.segment(i * d, d) = t + S * M.U.row(i).transpose();
    const Eigen::VectorXd Hg = H * g;
    CHECK(Hg.norm() < 1e-10 * H.norm() * g.norm());
  }
}

TEST_CASE("fact 4: x(u) does not depend on the gauge treatment", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh M = jittered_mesh(d, 8);
    const ModifiedBI mbi(M.U, M.T);
    const int n = static_cast<int>(M.U.rows());
    const Eigen::MatrixXd X = smooth_deform(M.U, 0.4);
    const VertexMatrices Ms = mbi.solve(X);
    // Alternative treatment: minimum-norm solution by the pseudo-inverse of the dense matrix
    // (eigenvalues below 1e-9 max dropped), i.e. m orthogonal to the null space.
    const Eigen::MatrixXd H =
        Eigen::MatrixXd(mbi.alpha() * mbi.vibr_hessian_mm() + mbi.beta() * mbi.disc_hessian_mm());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
    Eigen::VectorXd inv = es.eigenvalues();
    for (int i = 0; i < inv.size(); ++i) inv(i) = inv(i) > 1e-9 * inv.maxCoeff() ? 1 / inv(i) : 0;
    VertexMatrices Mp(n * d, d);
    for (int c = 0; c < d; ++c) {
      const Eigen::VectorXd rhs = -mbi.beta() * (mbi.disc_hessian_mx() * X.col(c));
      const Eigen::VectorXd m =
          es.eigenvectors() * inv.asDiagonal() * (es.eigenvectors().transpose() * rhs);
      for (int i = 0; i < n; ++i)
        for (int r = 0; r < d; ++r) Mp(i * d + c, r) = m(i * d + r);
    }
    CHECK(rel(Ms, Mp) > 1e-3);  // the two gauges really differ ...
    const Eigen::MatrixXd a = sample_field(M, X, Ms, 200, 9), b = sample_field(M, X, Mp, 200, 9);
    CHECK(rel(a, b) < 1e-9);  // ... but the field is the same (tolerance 1e-9 relative)
    // A third gauge: the solver on a renumbered mesh (vertex order reversed) pins other unknowns.
    Mesh R = M;
    for (int i = 0; i < n; ++i) R.U.row(n - 1 - i) = M.U.row(i);
    for (int e = 0; e < M.T.rows(); ++e)
      for (int k = 0; k <= d; ++k) R.T(e, k) = n - 1 - M.T(e, k);
    const Eigen::MatrixXd XR = X.colwise().reverse();
    const ModifiedBI mr(R.U, R.T);
    const VertexMatrices MR = mr.solve(XR);
    const Eigen::MatrixXd c = sample_field(R, XR, MR, 200, 9);  // same elements & bary samples
    CHECK(rel(c, a) < 1e-9);
  }
}

TEST_CASE("fact 5: Bezier form equals the defining formula, fact 6: Jacobian and normals", "[modified_bi][evaluate]") {
  for (int d : {2, 3}) {
    const Mesh M = jittered_mesh(d, 10);
    const int n = static_cast<int>(M.U.rows());
    const ModifiedBI mbi(M.U, M.T);
    const Eigen::MatrixXd X = smooth_deform(M.U, 0.5);
    for (const VertexMatrices& Mm : {mbi.solve(X), VertexMatrices(random_matrix(n * d, d, 51))}) {
      const BezierPoints B = mbi.bezier(X, Mm);
      std::mt19937 rng(12);
      std::uniform_real_distribution<double> uni(0.0, 1.0);
      Eigen::MatrixXd P(500, d);
      for (int i = 0; i < P.rows(); ++i)
        for (int c = 0; c < d; ++c) P(i, c) = uni(rng);
      const Embedding emb = embed(M.U, M.T, P);
      Eigen::MatrixXd pos;
      evaluate<double>(B, emb, pos, 2);
      double err = 0, jerr = 0;
      for (int i = 0; i < P.rows(); ++i) {
        const int e = emb.element(i);
        const Eigen::VectorXd ref = evaluate_reference(M.U, M.T, X, Mm, e, P.row(i).transpose());
        err = std::max(err, (pos.row(i).transpose() - ref).norm());
        // analytic Jacobian vs central differences of the defining formula (h = 1e-5)
        const Eigen::MatrixXd J = jacobian(M.U, M.T, B, e, emb.bary.row(i).transpose());
        Eigen::MatrixXd Jfd(d, d);
        const double h = 1e-5;
        for (int r = 0; r < d; ++r) {
          Eigen::VectorXd up = P.row(i).transpose(), um = up;
          up(r) += h;
          um(r) -= h;
          Jfd.col(r) = (evaluate_reference(M.U, M.T, X, Mm, e, up) - evaluate_reference(M.U, M.T, X, Mm, e, um)) / (2 * h);
        }
        jerr = std::max(jerr, (J - Jfd).norm() / J.norm());
      }
      CHECK(err < 1e-12);   // same quadratic, different arithmetic
      CHECK(jerr < 1e-7);   // finite-difference truncation is O(h^2) but the field is quadratic
      // normals: n' = cof(J) n is orthogonal to J t for every t orthogonal to n
      Eigen::MatrixXd nr = random_matrix(P.rows(), d, 13);
      nr.rowwise().normalize();
      Eigen::MatrixXd pos2, nout;
      evaluate<double>(B, emb, nr, pos2, nout, 3);
      CHECK((pos2 - pos).cwiseAbs().maxCoeff() == 0.0);
      double orth = 0, unit = 0, side = 1;
      for (int i = 0; i < P.rows(); ++i) {
        const Eigen::MatrixXd J = jacobian(M.U, M.T, B, emb.element(i), emb.bary.row(i).transpose());
        const Eigen::VectorXd nv = nr.row(i).transpose(), no = nout.row(i).transpose();
        unit = std::max(unit, std::abs(no.norm() - 1));
        const Eigen::MatrixXd Pt = Eigen::MatrixXd::Identity(d, d) - nv * nv.transpose();
        const Eigen::MatrixXd JT = J * Pt;  // images of the tangent directions
        orth = std::max(orth, (JT.transpose() * no).norm() / J.norm());
        // orientation: n' . (J n) > 0 when det J > 0 (sidedness is kept)
        side = std::min(side, J.determinant() > 0 ? no.dot(J * nv) : 1.0);
      }
      CHECK(orth < 1e-12);
      CHECK(unit < 1e-12);
      CHECK(side > 0);
    }
  }
}

TEST_CASE("fact 7: scaling rest and deformed meshes by s scales x(u) by s", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh M = jittered_mesh(d, 14);
    const Eigen::MatrixXd X = smooth_deform(M.U, 0.4);
    const ModifiedBI base(M.U, M.T);
    const Eigen::MatrixXd f0 = sample_field(M, X, base.solve(X), 100, 15);
    for (double s : {0.01, 3.7, 250.0}) {
      Mesh S = M;
      S.U *= s;
      const Eigen::MatrixXd XS = s * X;
      const ModifiedBI scaled(S.U, S.T);
      const Eigen::MatrixXd fs = sample_field(S, XS, scaled.solve(XS), 100, 15);
      CHECK(rel(fs, s * f0) < 1e-9);
      CHECK(scaled.beta() == Approx(base.beta() / s).epsilon(1e-9));
    }
  }
}

TEST_CASE("fact 8: interpolation x(u_k) = x_k and affine reproduction", "[modified_bi]") {
  for (int d : {2, 3}) {
    for (bool pin : {false, true}) {
      const Mesh M = jittered_mesh(d, 16);
      const int n = static_cast<int>(M.U.rows());
      Options o;
      o.pin_boundary = pin;
      const ModifiedBI mbi(M.U, M.T, o);
      const Eigen::MatrixXd X = smooth_deform(M.U, 0.5);
      const VertexMatrices Mm = mbi.solve(X);
      // vertices are reproduced
      const Embedding ev = embed(M.U, M.T, M.U);
      Eigen::MatrixXd pos;
      evaluate<double>(mbi.bezier(X, Mm), ev, pos, 1);
      CHECK((pos - X).cwiseAbs().maxCoeff() < 1e-12);
      // affine X: the field is that map, E_total = 0
      const Eigen::MatrixXd A = Eigen::MatrixXd::Identity(d, d) + 0.4 * random_matrix(d, d, 17);
      const Eigen::RowVectorXd b = random_matrix(1, d, 18);
      const Eigen::MatrixXd XA = (M.U * A.transpose()).rowwise() + b;
      const VertexMatrices MA = mbi.solve(XA);
      const DiscontinuityTable t = discontinuity_table(mbi, XA, MA);
      const double scale = mbi.alpha() * vibration_energy(M.U, M.T, random_matrix(n * d, d, 2));
      CHECK(t.e_total < 1e-20 * std::max(1.0, scale));
      const Eigen::MatrixXd f = sample_field(M, XA, MA, 100, 19);
      std::mt19937 rng(19);
      std::uniform_int_distribution<int> pick(0, static_cast<int>(M.T.rows()) - 1);
      Eigen::MatrixXd g(100, d);
      for (int s = 0; s < 100; ++s) {
        const int e = pick(rng);
        const Eigen::VectorXd u = point_of(M.U, M.T, e, random_bary(d, rng));
        g.row(s) = (A * u).transpose() + b;
      }
      CHECK(rel(f, g) < 1e-10);
    }
  }
}

TEST_CASE("fact 9: boundary-pinned variant", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh M = jittered_mesh(d, 20);
    const int n = static_cast<int>(M.U.rows());
    Options o;
    o.pin_boundary = true;
    const ModifiedBI pinned(M.U, M.T, o);
    const ModifiedBI free(M.U, M.T);
    CHECK(pinned.null_space_dim() == 0);
    CHECK(pinned.pin_boundary());
    const Eigen::MatrixXd X = smooth_deform(M.U, 0.5);
    const VertexMatrices Mp = pinned.solve(X), Mf = free.solve(X);
    const Eigen::VectorXi bv = boundary_vertices(n, M.T);
    double on_boundary = 0;
    for (int i = 0; i < n; ++i)
      if (bv(i)) on_boundary = std::max(on_boundary, Mp.middleRows(i * d, d).cwiseAbs().maxCoeff());
    CHECK(on_boundary == 0.0);
    CHECK(Mp.cwiseAbs().maxCoeff() > 0);  // interior vertices still get M
    // constrained minimum >= free minimum; both below BI (M = 0) which is feasible for both
    const DiscontinuityTable tp = discontinuity_table(pinned, X, Mp);
    const DiscontinuityTable tf = discontinuity_table(free, X, Mf);
    const double bi_total = pinned.beta() * tp.bi.mean * tp.faces;
    CHECK(tp.e_total >= tf.e_total * (1 - 1e-9));
    CHECK(tp.e_total <= bi_total * (1 + 1e-9));
    // edges of boundary faces stay straight: on a boundary edge only M of its two boundary
    // vertices enter P_ij, so P_ij is the edge midpoint (control polygon is a straight line)
    const BezierPoints B = pinned.bezier(X, Mp);
    const int K = (d + 1) * (d + 2) / 2;
    const auto& edges = bezier_edges(d);
    double dev = 0;
    for (int e = 0; e < M.T.rows(); ++e)
      for (size_t s = 0; s < edges.size(); ++s) {
        const int i = M.T(e, edges[s].first), j = M.T(e, edges[s].second);
        if (!bv(i) || !bv(j)) continue;
        dev = std::max(dev, (B.row(e * K + d + 1 + s) - 0.5 * (X.row(i) + X.row(j))).norm());
      }
    CHECK(dev == 0.0);
  }
}

TEST_CASE("fact 11: dense operator and sparse solves agree, set_alpha equals a fresh precompute", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh M = jittered_mesh(d, 23);
    const Eigen::MatrixXd X = smooth_deform(M.U, 0.3);
    Options od, os;
    od.solve_path = SolvePath::Dense;
    os.solve_path = SolvePath::Sparse;
    ModifiedBI a(M.U, M.T, od);
    const ModifiedBI b(M.U, M.T, os);
    CHECK(a.dense_operator());
    CHECK(!b.dense_operator());
    CHECK(rel(a.solve(X), b.solve(X)) < 1e-10);
    a.set_alpha(0.37);
    Options o3 = os;
    o3.alpha = 0.37;
    const ModifiedBI c(M.U, M.T, o3);
    CHECK(a.alpha() == 0.37);
    CHECK(a.beta() == c.beta());  // beta does not depend on alpha
    CHECK(rel(a.solve(X), c.solve(X)) < 1e-10);
  }
}

TEST_CASE("fact 13: alpha <= 0 and other bad input are rejected", "[modified_bi]") {
  const Mesh M = jittered_mesh(3, 24);
  Options o;
  o.alpha = -0.1;
  CHECK_THROWS_WITH(ModifiedBI(M.U, M.T, o), Catch::Contains("alpha"));
  o.alpha = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(ModifiedBI(M.U, M.T, o), Error);
  o.alpha = 0.1;
  o.beta = -1;
  CHECK_THROWS_WITH(ModifiedBI(M.U, M.T, o), Catch::Contains("beta"));
  ModifiedBI mbi(M.U, M.T);
  CHECK(mbi.alpha() == 0.1);  // default in 3D
  CHECK_THROWS_WITH(mbi.set_alpha(0.0), Catch::Contains("alpha"));
  CHECK_THROWS_AS(mbi.set_alpha(-1.0), Error);
  CHECK(mbi.alpha() == 0.1);  // unchanged after a rejected call
  Eigen::MatrixXd X = M.U;
  X(3, 1) = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(mbi.solve(X), Catch::Contains("vertex 3"));
  CHECK_THROWS_AS(mbi.solve(M.U.topRows(5)), Error);
  const Mesh M2 = jittered_mesh(2, 24);
  CHECK(ModifiedBI(M2.U, M2.T).alpha() == 0.2);  // default in 2D
  // a single element has no interior face
  CHECK_THROWS_WITH(ModifiedBI(M.U, M.T.topRows(1)), Catch::Contains("interior faces"));
}

TEST_CASE("fact 12: twisted bar, modified-BI discontinuity at least 100x below BI", "[modified_bi][table]") {
  // 2 x 2 x 8 unit cells (bar 8 x 2 x 2 along x), twisted 90 degrees about x, bent by
  // z += 0.1 L (x/L)^2 (tip lifted by 0.8 = 10% of the length).
  const int nx = 8, ny = 2, nz = 2;
  Mesh M = box_tet_mesh(nx, ny, nz, Eigen::Vector3d(8, 2, 2));
  const Eigen::MatrixXd X = twist_bend(M.U, M_PI / 2, 0.1);
  ModifiedBI mbi(M.U, M.T);
  const int faces = static_cast<int>(interior_faces(M.T).rows());
  // Every printed number is asserted below. Faces: 4 per tet, minus 2 boundary triangles per
  // boundary square, each interior face shared by two tets.
  const int boundary_squares = 2 * (nx * ny + ny * nz + nz * nx);
  CHECK(faces == (4 * static_cast<int>(M.T.rows()) - 2 * boundary_squares) / 2);
  // beta: the Frobenius rule of fact 7, computed here from the m-blocks
  CHECK(mbi.beta() == Approx(mbi.vibr_hessian_mm().norm() / mbi.disc_hessian_mm().norm()).epsilon(1e-12));
  std::printf("twisted bar 8x2x2 cells, 90 deg twist, bend 0.1: %d faces, beta = %.4g\n", faces, mbi.beta());
  std::printf("%6s | %10s %10s %10s | %10s %10s %10s | %8s %8s %8s\n", "alpha", "BI mean", "BI std",
              "BI max", "mBI mean", "mBI std", "mBI max", "r mean", "r std", "r max");
  // mean, population std and max of per-face energies, computed here (not by summarize)
  auto stats = [](const Eigen::VectorXd& v) {
    const double mean = v.sum() / static_cast<double>(v.size());
    const double var = (v.array() - mean).square().sum() / static_cast<double>(v.size());
    return Summary{mean, std::sqrt(var), v.maxCoeff()};
  };
  const VertexMatrices zero = VertexMatrices::Zero(M.U.rows() * 3, 3);
  const Summary bi = stats(face_discontinuity(M.U, M.T, X, zero));
  auto same = [](const Summary& a, const Summary& b) {
    CHECK(a.mean == Approx(b.mean).epsilon(1e-12));
    CHECK(a.std == Approx(b.std).epsilon(1e-10));
    CHECK(a.max == Approx(b.max).epsilon(1e-12));
  };
  const std::vector<double> alphas{1.0, 0.25, 0.1, 0.01};  // decreasing
  std::vector<DiscontinuityTable> rows;
  for (double alpha : alphas) {
    mbi.set_alpha(alpha);
    const VertexMatrices Mm = mbi.solve(X);
    const DiscontinuityTable t = discontinuity_table(mbi, X, Mm);
    std::printf("%6.3g | %10.4g %10.4g %10.4g | %10.4g %10.4g %10.4g | %8.1f %8.1f %8.1f\n", alpha,
                t.bi.mean, t.bi.std, t.bi.max, t.modified_bi.mean, t.modified_bi.std,
                t.modified_bi.max, t.ratio.mean, t.ratio.std, t.ratio.max);
    INFO("alpha " << alpha);
    CHECK(t.faces == faces);
    // BI columns: the statistics of the per-face energies with M = 0, whatever alpha
    same(t.bi, bi);
    // modified-BI columns: the statistics of its own per-face energies
    const Eigen::VectorXd e_mbi = face_discontinuity(M.U, M.T, X, Mm);
    same(t.modified_bi, stats(e_mbi));
    CHECK(t.e_disc == Approx(e_mbi.sum()).epsilon(1e-12));
    CHECK(t.e_vibr == Approx(vibration_energy(M.U, M.T, Mm)).epsilon(1e-12));
    CHECK(t.e_total == Approx(alpha * t.e_vibr + mbi.beta() * t.e_disc).epsilon(1e-12));
    // ratio columns: BI over modified-BI, statistic by statistic
    CHECK(t.ratio.mean == Approx(t.bi.mean / t.modified_bi.mean).epsilon(1e-12));
    CHECK(t.ratio.std == Approx(t.bi.std / t.modified_bi.std).epsilon(1e-12));
    CHECK(t.ratio.max == Approx(t.bi.max / t.modified_bi.max).epsilon(1e-12));
    // M = 0 (BI, E_vibr = 0) is feasible, so the minimum is at most BI's energy, strictly below
    // it here since BI is not stationary: the mean ratio exceeds 1
    CHECK(t.e_total <= mbi.beta() * bi.mean * faces * (1 + 1e-12));
    CHECK(t.ratio.mean > 1);
    if (alpha == 0.1) CHECK(t.ratio.mean >= 100);  // paper Table 2: two orders of magnitude
    rows.push_back(t);
  }
  // Trade-off of minimising alpha E_vibr + beta E_disc: for alpha' < alpha, adding the two
  // optimality inequalities gives (alpha - alpha') (E_vibr(alpha') - E_vibr(alpha)) >= 0 and
  // then beta (E_disc(alpha) - E_disc(alpha')) >= alpha' (E_vibr(alpha') - E_vibr(alpha)) >= 0:
  // E_disc (so the modified-BI mean) does not grow and E_vibr does not shrink as alpha decreases;
  // hence the mean ratio grows. Strict here: every alpha gives a different M.
  for (size_t k = 1; k < rows.size(); ++k) {
    INFO("alpha " << alphas[k - 1] << " -> " << alphas[k]);
    CHECK(rows[k].modified_bi.mean < rows[k - 1].modified_bi.mean);
    CHECK(rows[k].e_vibr > rows[k - 1].e_vibr);
    CHECK(rows[k].ratio.mean > rows[k - 1].ratio.mean);
  }
}

TEST_CASE("fact 4 and 13 on structured meshes: gauge only with alpha > 0, extra E_disc null modes", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh M = d == 3 ? box_tet_mesh(3, 3, 3) : square_tri_mesh(5, 4);  // no jitter
    const ModifiedBI mbi(M.U, M.T);
    const int expected = d + d * (d - 1) / 2;
    auto nulls = [](const Eigen::MatrixXd& H) {
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
      const Eigen::VectorXd ev = es.eigenvalues();
      int k = 0;
      for (int i = 0; i < ev.size(); ++i) k += ev(i) < 1e-9 * ev.maxCoeff();
      return k;
    };
    const Eigen::MatrixXd Hd = Eigen::MatrixXd(mbi.disc_hessian_mm());
    const Eigen::MatrixXd Ht = Eigen::MatrixXd(mbi.alpha() * mbi.vibr_hessian_mm()) + mbi.beta() * Hd;
    CHECK(nulls(Ht) == expected);
    const int disc_nulls = nulls(Hd);
    std::printf("structured %dD mesh: E_disc alone has %d null modes, E_total %d\n", d, disc_nulls, expected);
    CHECK(disc_nulls > expected);  // why alpha must be > 0
  }
}

TEST_CASE("rigid motion of the rest mesh: the field moves with it", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh M = jittered_mesh(d, 25);
    const Eigen::MatrixXd X = smooth_deform(M.U, 0.4);
    const Eigen::MatrixXd Q = random_rotation(d, 26);
    const Eigen::RowVectorXd t = random_matrix(1, d, 27);
    Mesh R = M;
    R.U = (M.U * Q.transpose()).rowwise() + t;  // rotated rest mesh, same deformed X
    const ModifiedBI a(M.U, M.T), b(R.U, R.T);
    // x(u) is a function of the rest point: x_R(Q u + t) = x(u)
    const Eigen::MatrixXd fa = sample_field(M, X, a.solve(X), 100, 28);
    const Eigen::MatrixXd fb = sample_field(R, X, b.solve(X), 100, 28);  // same elements/bary
    CHECK(rel(fb, fa) < 1e-9);
  }
}

TEST_CASE("fact 4 per face-connected part: two separate meshes, and parts joined at a vertex", "[modified_bi]") {
  for (int d : {2, 3}) {
    const Mesh A = jittered_mesh(d, 29);
    const int n = static_cast<int>(A.U.rows());
    Mesh B;
    B.U.resize(2 * n, d);
    B.U << A.U, A.U.rowwise() + Eigen::RowVectorXd::Constant(d, 3.0);  // disjoint copy
    B.T.resize(2 * A.T.rows(), d + 1);
    B.T << A.T, A.T.array() + n;
    const ModifiedBI two(B.U, B.T);
    const int k = d + d * (d - 1) / 2;
    CHECK(two.null_space_dim() == 2 * k);
    // each part behaves as if alone
    const ModifiedBI one(A.U, A.T);
    const Eigen::MatrixXd X = smooth_deform(A.U, 0.4);
    Eigen::MatrixXd XB(2 * n, d);
    XB << X, X;
    const Eigen::MatrixXd f1 = sample_field(A, X, one.solve(X), 100, 30);
    Mesh B2 = B;  // sample the second copy: same elements shifted by A.T.rows()
    B2.T = B.T.bottomRows(A.T.rows());
    const Eigen::MatrixXd f2 = sample_field(B2, XB, two.solve(XB), 100, 30);
    CHECK(rel(f2, f1) < 1e-9);
    // the copy's elements use vertex `shared` of the first part instead of their own: the
    // parts share a vertex but no face -> rejected with an error naming the vertex
    Mesh C = B;
    const int shared = A.T(0, 0);
    for (int e = static_cast<int>(A.T.rows()); e < C.T.rows(); ++e)
      for (int j = 0; j <= d; ++j)
        if (C.T(e, j) == n + shared) C.T(e, j) = shared;
    CHECK_THROWS_WITH(ModifiedBI(C.U, C.T), Catch::Contains("vertex " + std::to_string(shared)));
  }
}
