// Phong deformation (interp/phong.hpp): the vertex weights, affine reproduction, the kernel
// against the defining formula (f_C + f_V) / 2, and how it ranks between BI and modified-BI on
// smoothly twisted and bent bars (discontinuity and error against the closed-form map).
#include <catch2/catch.hpp>

#include "test_support.hpp"

#include <cmath>
#include <random>

using namespace mbi;
using namespace mbi::interp;

namespace {

// r_e = (rest centroid of e) - u_i for the incident elements of vertex i, in Phong's order.
std::vector<Eigen::VectorXd> offsets(const Phong& ph, const Eigen::MatrixXd& U,
                                     const Eigen::MatrixXi& T, int i) {
  std::vector<Eigen::VectorXd> r;
  const int d = static_cast<int>(U.cols());
  for (int e : ph.incident_elements(i)) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(d);
    for (int k = 0; k <= d; ++k) c += U.row(T(e, k)).transpose() / (d + 1);
    r.push_back(c - U.row(i).transpose());
  }
  return r;
}

// F_e = D_s D_m^-1 written independently: the unique linear map with F (u_k - u_0) = x_k - x_0.
Eigen::MatrixXd element_F(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T,
                          const Eigen::MatrixXd& X, int e) {
  const int d = static_cast<int>(U.cols());
  Eigen::MatrixXd Dm(d, d), Ds(d, d);
  for (int k = 0; k < d; ++k) {
    Dm.col(k) = (U.row(T(e, k + 1)) - U.row(T(e, 0))).transpose();
    Ds.col(k) = (X.row(T(e, k + 1)) - X.row(T(e, 0))).transpose();
  }
  return Dm.transpose().partialPivLu().solve(Ds.transpose()).transpose();
}

// Dense points on a regular grid over the bounding box of U, boundary included.
Eigen::MatrixXd grid_points(const Eigen::MatrixXd& U, int per_axis) {
  const int d = static_cast<int>(U.cols());
  const Eigen::RowVectorXd lo = U.colwise().minCoeff(), hi = U.colwise().maxCoeff();
  const int p = static_cast<int>(std::pow(per_axis, d));
  Eigen::MatrixXd P(p, d);
  for (int q = 0; q < p; ++q) {
    int rest = q;
    for (int c = 0; c < d; ++c) {
      const int k = rest % per_axis;
      rest /= per_axis;
      P(q, c) = lo(c) + (hi(c) - lo(c)) * k / (per_axis - 1);
    }
  }
  return P;
}

}  // namespace

TEST_CASE("phong: weights sum to 1 and satisfy the correction identity", "[phong]") {
  for (int d : {2, 3}) {
    for (unsigned seed : {1u, 2u, 3u}) {
      const test::Mesh m = test::jittered_mesh(d, seed);
      const Phong ph(m.U, m.T);
      CHECK(ph.fallback_vertices() == 0);
      for (int i = 0; i < m.U.rows(); ++i) {
        INFO("d " << d << " seed " << seed << " vertex " << i);
        const std::vector<double>& w = ph.weights(i);
        REQUIRE(w.size() == ph.incident_elements(i).size());
        REQUIRE(!w.empty());
        double sum = 0;
        for (double x : w) sum += x;
        CHECK(std::abs(sum - 1) < 1e-12);
        // lambda = -(I + sum rh rh^T)^-1 sum rh, so sum (1 + lambda . rh) rh = -lambda
        const std::vector<Eigen::VectorXd> r = offsets(ph, m.U, m.T, i);
        const Eigen::VectorXd lambda = ph.correction(i);
        Eigen::VectorXd s = Eigen::VectorXd::Zero(d);
        for (const Eigen::VectorXd& re : r) s += (1 + lambda.dot(re.normalized())) * re.normalized();
        CHECK((s + lambda).norm() < 1e-12);
        // w_e proportional to (1 + lambda . rh_e) / |r_e|
        for (size_t a = 0; a < r.size(); ++a) {
          const double raw = (1 + lambda.dot(r[a].normalized())) / r[a].norm();
          const double raw0 = (1 + lambda.dot(r[0].normalized())) / r[0].norm();
          CHECK(std::abs(w[a] * raw0 - w[0] * raw) < 1e-12 * (std::abs(w[a] * raw0) + 1e-300));
        }
      }
    }
  }
}

TEST_CASE("phong: F_i = A for affine deformations, so affine maps are reproduced", "[phong]") {
  for (int d : {2, 3}) {
    const test::Mesh m = test::jittered_mesh(d, 11);
    const Phong ph(m.U, m.T);
    const Eigen::MatrixXd A = test::random_rotation(d, 5) * (Eigen::MatrixXd::Identity(d, d) +
                                                             0.3 * test::random_matrix(d, d, 6));
    const Eigen::RowVectorXd b = test::random_matrix(1, d, 7);
    const Eigen::MatrixXd X = (m.U * A.transpose()).rowwise() + b;
    const Eigen::MatrixXd F = ph.vertex_gradients(X);
    for (int i = 0; i < m.U.rows(); ++i)
      CHECK((F.middleRows(i * d, d) - A).cwiseAbs().maxCoeff() < 1e-12);
    CHECK((ph.M(X) - 0.5 * F).cwiseAbs().maxCoeff() == 0);
    const Eigen::MatrixXd P = grid_points(m.U, d == 3 ? 9 : 25);
    const Embedding emb = embed(m.U, m.T, P);
    Eigen::MatrixXd x;
    evaluate<double>(bezier_points(m.U, m.T, X, ph.M(X)), emb, x);
    const Eigen::MatrixXd expect = (P * A.transpose()).rowwise() + b;
    CHECK((x - expect).cwiseAbs().maxCoeff() < 1e-12);
  }
}

TEST_CASE("phong: the kernel with M = F/2 equals (f_C + f_V) / 2 at random points", "[phong]") {
  for (int d : {2, 3}) {
    const test::Mesh m = test::jittered_mesh(d, 21);
    const Eigen::MatrixXd X = test::smooth_deform(m.U, 0.4);
    const Phong ph(m.U, m.T);
    // F_i from its definition, with F_e computed independently
    std::vector<Eigen::MatrixXd> Fv(static_cast<size_t>(m.U.rows()), Eigen::MatrixXd::Zero(d, d));
    for (int i = 0; i < m.U.rows(); ++i)
      for (size_t a = 0; a < ph.incident_elements(i).size(); ++a)
        Fv[static_cast<size_t>(i)] += ph.weights(i)[a] * element_F(m.U, m.T, X, ph.incident_elements(i)[a]);
    std::mt19937 rng(4);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(m.T.rows()) - 1);
    const int p = 400;
    Embedding emb;
    emb.element.resize(p);
    emb.bary.resize(p, d + 1);
    for (int q = 0; q < p; ++q) {
      emb.element(q) = pick(rng);
      emb.bary.row(q) = test::random_bary(d, rng).transpose();
    }
    Eigen::MatrixXd x;
    evaluate<double>(bezier_points(m.U, m.T, X, ph.M(X)), emb, x, 1);
    double err = 0;
    for (int q = 0; q < p; ++q) {
      const int e = emb.element(q);
      const Eigen::VectorXd u = test::point_of(m.U, m.T, e, emb.bary.row(q).transpose());
      Eigen::VectorXd fC = Eigen::VectorXd::Zero(d), fV = Eigen::VectorXd::Zero(d);
      for (int k = 0; k <= d; ++k) {
        const int i = m.T(e, k);
        const Eigen::VectorXd xi = X.row(i).transpose();
        fC += emb.bary(q, k) * xi;
        fV += emb.bary(q, k) * (xi + Fv[static_cast<size_t>(i)] * (u - m.U.row(i).transpose()));
      }
      err = std::max(err, (x.row(q).transpose() - 0.5 * (fC + fV)).cwiseAbs().maxCoeff());
    }
    INFO("d " << d << ": max |kernel - (f_C + f_V)/2| = " << err);
    CHECK(err < 1e-12);
  }
}

namespace {

// A bar along x bent into a circular arc (total angle `angle`) about its centre line y = cy;
// isometric along the centre line. Returns positions (p x 2) and, optionally, Jacobians.
Eigen::MatrixXd arc_bend(const Eigen::MatrixXd& P, double L, double cy, double angle,
                         Eigen::MatrixXd* J = nullptr) {
  const double k = angle / L;
  Eigen::MatrixXd X(P.rows(), 2);
  if (J) J->resize(2 * P.rows(), 2);
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const double t = k * P(i, 0), y = P(i, 1) - cy, c = std::cos(t), s = std::sin(t);
    X(i, 0) = s / k - y * s;
    X(i, 1) = cy + (1 - c) / k + y * c;
    if (J) J->middleRows(2 * i, 2) << c - y * k * c, -s, s - y * k * s, c;
  }
  return X;
}

// Jacobian of test::twist_bend (bar along x of length L, twist about the axis through
// (cy, cz), bend in z) at points P, in closed form: (p 3) x 3.
Eigen::MatrixXd twist_bend_jacobian(const Eigen::MatrixXd& U, const Eigen::MatrixXd& P,
                                    double twist, double bend) {
  const double L = U.col(0).maxCoeff();
  const double cy = 0.5 * (U.col(1).minCoeff() + U.col(1).maxCoeff());
  const double cz = 0.5 * (U.col(2).minCoeff() + U.col(2).maxCoeff());
  Eigen::MatrixXd J(3 * P.rows(), 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) {
    const double s = P(i, 0) / L, a = twist * s, c = std::cos(a), sn = std::sin(a);
    const double y = P(i, 1) - cy, z = P(i, 2) - cz;
    J.middleRows(3 * i, 3) << 1, 0, 0,
        (-sn * y - c * z) * twist / L, c, -sn,
        (c * y - sn * z) * twist / L + 2 * bend * s, sn, c;
  }
  return J;
}

struct Ranking {
  double disc_bi, disc_phong, disc_mbi;
  Accuracy acc_bi, acc_phong, acc_mbi;
};

Ranking rank(const test::Mesh& m, const Eigen::MatrixXd& X, const Eigen::MatrixXd& P,
             const Eigen::MatrixXd& exact, const Eigen::MatrixXd& exact_J, double alpha) {
  const ModifiedBI solver(m.U, m.T, {.alpha = alpha});
  const Phong ph(m.U, m.T);
  const VertexMatrices Mm = solver.solve(X), Mp = ph.M(X);
  const VertexMatrices Z = VertexMatrices::Zero(Mm.rows(), Mm.cols());
  const DiscontinuityTable t = discontinuity_table(solver, X, Mm, Mp);
  const Embedding emb = embed(m.U, m.T, P);
  Ranking r;
  r.disc_bi = t.bi.mean;
  r.disc_phong = t.phong->mean;
  r.disc_mbi = t.modified_bi.mean;
  r.acc_bi = accuracy(bezier_points(m.U, m.T, X, Z), emb, P, exact, exact_J);
  r.acc_phong = accuracy(bezier_points(m.U, m.T, X, Mp), emb, P, exact, exact_J);
  r.acc_mbi = accuracy(bezier_points(m.U, m.T, X, Mm), emb, P, exact, exact_J);
  return r;
}

void check_ranking(const Ranking& r) {
  INFO("mean face discontinuity: BI " << r.disc_bi << ", Phong " << r.disc_phong
       << ", modified-BI " << r.disc_mbi << "; BI/Phong " << r.disc_bi / r.disc_phong
       << ", Phong/modified-BI " << r.disc_phong / r.disc_mbi);
  INFO("RMS position error / size: BI " << r.acc_bi.position_rms << ", Phong "
       << r.acc_phong.position_rms << ", modified-BI " << r.acc_mbi.position_rms << "; BI/Phong "
       << r.acc_bi.position_rms / r.acc_phong.position_rms << ", Phong/modified-BI "
       << r.acc_phong.position_rms / r.acc_mbi.position_rms);
  INFO("RMS gradient error / |F|: BI " << r.acc_bi.gradient_rms << ", Phong "
       << r.acc_phong.gradient_rms << ", modified-BI " << r.acc_mbi.gradient_rms);
  CHECK(r.disc_bi > r.disc_phong);
  CHECK(r.disc_phong > r.disc_mbi);
  CHECK(r.acc_bi.position_rms > r.acc_phong.position_rms);
  CHECK(r.acc_phong.position_rms > r.acc_mbi.position_rms);
  CHECK(r.acc_bi.gradient_rms > r.acc_phong.gradient_rms);
  CHECK(r.acc_phong.gradient_rms > r.acc_mbi.gradient_rms);
  WARN("BI/Phong disc " << r.disc_bi / r.disc_phong << ", Phong/mBI disc "
       << r.disc_phong / r.disc_mbi << "; BI/Phong pos " << r.acc_bi.position_rms / r.acc_phong.position_rms
       << ", Phong/mBI pos " << r.acc_phong.position_rms / r.acc_mbi.position_rms << "; grad rms BI "
       << r.acc_bi.gradient_rms << " Phong " << r.acc_phong.gradient_rms << " mBI " << r.acc_mbi.gradient_rms);
}

}  // namespace

TEST_CASE("phong: BI > Phong > modified-BI on twisted and bent 3D bars", "[phong][ranking]") {
  const double pi = std::acos(-1.0);
  for (int cells : {1, 2, 3}) {
    const int nx = 4 * cells, ny = cells;
    const test::Mesh m = test::box_tet_mesh(nx, ny, ny, Eigen::Vector3d(4, 1, 1));
    const Eigen::MatrixXd P = grid_points(m.U, 17);
    for (const auto& [twist, bend] : {std::pair{pi / 2, 0.1}, std::pair{pi / 4, 0.3}}) {
      INFO("3D bar " << nx << "x" << ny << "x" << ny << ", twist " << twist << " rad, bend " << bend);
      const Eigen::MatrixXd X = test::twist_bend(m.U, twist, bend);
      // the closed form at the dense points (twist_bend reads L, cy, cz off its argument: P
      // spans the same box as U)
      const Eigen::MatrixXd exact = test::twist_bend(P, twist, bend);
      const Eigen::MatrixXd exact_J = twist_bend_jacobian(m.U, P, twist, bend);
      check_ranking(rank(m, X, P, exact, exact_J, 0.1));
    }
  }
}

TEST_CASE("phong: BI > Phong > modified-BI on bent 2D bars", "[phong][ranking]") {
  const double pi = std::acos(-1.0);
  for (int cells : {1, 2, 4}) {
    const int nx = 6 * cells, ny = cells;
    const test::Mesh m = test::square_tri_mesh(nx, ny, Eigen::Vector2d(6, 1));
    const Eigen::MatrixXd P = grid_points(m.U, 61);
    for (double angle : {pi / 2, pi}) {
      INFO("2D bar " << nx << "x" << ny << ", bent by " << angle << " rad");
      const Eigen::MatrixXd X = arc_bend(m.U, 6, 0.5, angle);
      Eigen::MatrixXd exact_J;
      const Eigen::MatrixXd exact = arc_bend(P, 6, 0.5, angle, &exact_J);
      check_ranking(rank(m, X, P, exact, exact_J, 0.1));
    }
  }
}

TEST_CASE("accuracy: zero for an affine map, and the relative scales", "[phong][accuracy]") {
  const test::Mesh m = test::jittered_mesh(3, 4);
  const Eigen::MatrixXd A = 2.0 * test::random_rotation(3, 9);
  const Eigen::MatrixXd X = m.U * A.transpose();
  const Eigen::MatrixXd P = grid_points(m.U, 6);
  const Embedding emb = embed(m.U, m.T, P);
  Eigen::MatrixXd J(3 * P.rows(), 3);
  for (Eigen::Index q = 0; q < P.rows(); ++q) J.middleRows(3 * q, 3) = A;
  const Eigen::MatrixXd exact = P * A.transpose();
  const Accuracy a = accuracy(bezier_bi(X, m.T), emb, P, exact, J);
  CHECK(a.position_rms < 1e-14);
  CHECK(a.gradient_rms < 1e-13);
  CHECK(a.size == Approx(std::sqrt(3.0)));
  // a constant offset c of every exact point: position_rms = |c| / size; gradients unchanged
  const Eigen::RowVector3d c(0.3, 0.0, 0.4);
  const Accuracy b = accuracy(bezier_bi(X, m.T), emb, P, exact.rowwise() + c, J);
  CHECK(b.position_rms == Approx(0.5 / std::sqrt(3.0)));
  CHECK(b.position_max == Approx(0.5 / std::sqrt(3.0)));
  CHECK(b.gradient_rms < 1e-13);
  // exact gradients 2 A against the field's A: relative error 1/2
  const Accuracy g = accuracy(bezier_bi(X, m.T), emb, P, exact, 2 * J);
  CHECK(g.gradient_rms == Approx(0.5));
  CHECK_THROWS_AS(accuracy(bezier_bi(X, m.T), emb, P, exact.topRows(3), J), interp::Error);
}

TEST_CASE("phong: bad input is rejected", "[phong]") {
  const test::Mesh m = test::jittered_mesh(2, 1);
  const Phong ph(m.U, m.T);
  CHECK_THROWS_AS(ph.M(Eigen::MatrixXd::Zero(3, 2)), interp::Error);
  Eigen::MatrixXd X = m.U;
  X(2, 1) = std::nan("");
  CHECK_THROWS_AS(ph.M(X), interp::Error);
  Eigen::MatrixXi T = m.T;
  T(0, 1) = T(0, 0);
  CHECK_THROWS_AS(Phong(m.U, T), interp::Error);
}
