// Contact at embedded points through the embedding's transpose (method.md fact 16).
#include <mbi/pipeline/surface_contact.hpp>

#include <catch2/catch.hpp>
#include "common/grid_meshes.hpp"
#include <Eigen/Eigenvalues>
#include <limits>
#include <random>

using namespace mbi::pipeline;

namespace {

struct Setup {
  mbi::test::Mesh mesh;
  Eigen::MatrixXd points;  // p x 3 contact points, inside and on the box
  Eigen::VectorXd x;       // 3 n, a deformed pose
};

Setup setup() {
  Setup s;
  s.mesh = mbi::test::box_tet_mesh(3, 2, 2, Eigen::Vector3d(1.5, 1.0, 1.0));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0), w(-0.04, 0.04);
  s.points.resize(300, 3);
  for (int p = 0; p < 300; ++p) s.points.row(p) = Eigen::RowVector3d(1.5 * u(rng), u(rng), u(rng));
  const Eigen::Index n = s.mesh.U.rows();
  s.x.resize(3 * n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) s.x(3 * i + c) = s.mesh.U(i, c) + w(rng);
  return s;
}

std::vector<Collider> colliders() {
  return {Collider::plane({0, 0.3, 0}, {0.1, 1.0, 0.05}, 0.5), Collider::sphere({1.5, 1.0, 0.5}, 0.45)};
}

Eigen::VectorXd gradient(const SurfaceContact& c, const Eigen::VectorXd& x) {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  c.add_gradient(x, g);
  return g;
}

}  // namespace

TEST_CASE("surface contact: force = finite differences of the energy through the pipeline, "
          "BI, Phong and modified-BI", "[pipeline][contact]") {
  const Setup s = setup();
  for (Method m : {Method::BI, Method::Phong, Method::ModifiedBI}) {
    DeformerOptions opt;
    opt.method = m;
    auto deformer = std::make_shared<Deformer>(s.mesh.U, s.mesh.T, s.points, opt);
    SurfaceContact contact(deformer, colliders(), 1e4);
    const Eigen::VectorXd g = gradient(contact, s.x);
    REQUIRE(contact.energy(s.x) > 0);
    Eigen::VectorXd fd(s.x.size());
    const double eps = 1e-6;
    for (Eigen::Index k = 0; k < s.x.size(); ++k) {
      Eigen::VectorXd xp = s.x, xm = s.x;
      xp(k) += eps;
      xm(k) -= eps;
      fd(k) = (contact.energy(xp) - contact.energy(xm)) / (2 * eps);
    }
    INFO("method " << static_cast<int>(m));
    CHECK((fd - g).norm() <= 1e-6 * g.norm());
  }
}

TEST_CASE("surface contact: for BI the force is the per-element assembly of the point forces",
          "[pipeline][contact]") {
  const Setup s = setup();
  DeformerOptions opt;
  opt.method = Method::BI;
  auto deformer = std::make_shared<Deformer>(s.mesh.U, s.mesh.T, s.points, opt);
  SurfaceContact contact(deformer, colliders(), 1e4);
  const Eigen::MatrixXd P = contact.points(s.x);
  const mbi::interp::Embedding& emb = deformer->embedding();
  Eigen::VectorXd expect = Eigen::VectorXd::Zero(s.x.size());
  int touching = 0;
  for (Eigen::Index p = 0; p < P.rows(); ++p)
    for (const Collider& c : contact.colliders()) {
      const Distance d = signed_distance(c, P.row(p).transpose(), 0.0);
      if (d.value >= 0) continue;
      ++touching;
      for (int a = 0; a < 4; ++a)
        expect.segment<3>(3 * s.mesh.T(emb.element(p), a)) += emb.bary(p, a) * 1e4 * d.value * d.normal;
    }
  CHECK(touching > 20);
  CHECK((gradient(contact, s.x) - expect).norm() <= 1e-12 * expect.norm());
}

TEST_CASE("surface contact: the Hessian surrogate is PSD, inside the element pattern, and equals "
          "W^T K W for BI", "[pipeline][contact]") {
  const Setup s = setup();
  for (Method m : {Method::BI, Method::ModifiedBI}) {
    DeformerOptions opt;
    opt.method = m;
    auto deformer = std::make_shared<Deformer>(s.mesh.U, s.mesh.T, s.points, opt);
    SurfaceContact contact(deformer, colliders(), 1e4);
    std::vector<mbi::sim::NodeBlock> blocks;
    contact.hessian_blocks(s.x, blocks);
    REQUIRE(!blocks.empty());
    mbi::sim::Simulator sim(s.mesh.U, s.mesh.T, mbi::sim::Material{});
    const Eigen::Index N = s.x.size();
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(N, N);
    for (const auto& b : blocks) {
      CHECK(sim.adjacent(b.row, b.col));
      H.block<3, 3>(3 * b.row, 3 * b.col) += b.value;
      if (b.row != b.col) H.block<3, 3>(3 * b.col, 3 * b.row) += b.value.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H);
    CHECK(eig.eigenvalues().minCoeff() >= -1e-9 * eig.eigenvalues().maxCoeff());
    if (m == Method::BI) {
      // For BI and a plane the surrogate is the exact Hessian W^T K W (the normal is constant):
      // finite differences of the force.
      SurfaceContact flat(deformer, {colliders()[0]}, 1e4);
      std::vector<mbi::sim::NodeBlock> fb;
      flat.hessian_blocks(s.x, fb);
      Eigen::MatrixXd Hf = Eigen::MatrixXd::Zero(N, N);
      for (const auto& b : fb) {
        Hf.block<3, 3>(3 * b.row, 3 * b.col) += b.value;
        if (b.row != b.col) Hf.block<3, 3>(3 * b.col, 3 * b.row) += b.value.transpose();
      }
      Eigen::MatrixXd fdf(N, N);
      for (Eigen::Index k = 0; k < N; ++k) {
        Eigen::VectorXd xp = s.x, xm = s.x;
        xp(k) += 1e-7;
        xm(k) -= 1e-7;
        fdf.col(k) = (gradient(flat, xp) - gradient(flat, xm)) / 2e-7;
      }
      CHECK(Hf.norm() > 0);
      CHECK((fdf - Hf).norm() <= 1e-5 * Hf.norm());
    }
  }
}

TEST_CASE("surface contact: bad input is an Error naming what is wrong", "[pipeline][contact][errors]") {
  const Setup s = setup();
  auto deformer = std::make_shared<Deformer>(s.mesh.U, s.mesh.T, s.points);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH(SurfaceContact(deformer, colliders(), nan), Catch::Contains("contact stiffness"));
  CHECK_THROWS_WITH(SurfaceContact(deformer, colliders(), 0.0), Catch::Contains("contact stiffness"));
  auto bad = colliders();
  bad[1].friction = nan;
  CHECK_THROWS_WITH(SurfaceContact(deformer, bad, 1e4), Catch::StartsWith("collider 1: friction"));
  CHECK_THROWS_WITH(SurfaceContact(nullptr, colliders(), 1e4), Catch::Contains("deformer"));
  SurfaceContact ok(deformer, colliders(), 1e4);
  CHECK_THROWS_WITH(ok.energy(Eigen::VectorXd::Zero(5)), Catch::Contains("node positions must have"));
  CHECK_THROWS_WITH(ok.set_time(nan), Catch::Contains("time must be finite"));
}

TEST_CASE("surface contact: a cage dropped on a plane rests on its dense surface, not on the cage",
          "[pipeline][contact][sim]") {
  // Cage [0, 1]^3; contact points: a grid on the plane y = 0.1 inside it (the model's bottom).
  const auto cage = mbi::test::box_tet_mesh(2, 2, 2);
  Eigen::MatrixXd P(25, 3);
  for (int i = 0; i < 5; ++i)
    for (int k = 0; k < 5; ++k) P.row(5 * i + k) = Eigen::RowVector3d(0.1 + 0.2 * i, 0.1, 0.1 + 0.2 * k);
  DeformerOptions opt;
  opt.method = Method::ModifiedBI;
  auto deformer = std::make_shared<Deformer>(cage.U, cage.T, P, opt);
  const double floor = 0.05;
  auto contact = std::make_shared<SurfaceContact>(
      deformer, std::vector<Collider>{Collider::plane({0, floor, 0}, {0, 1, 0})}, 1e7);
  mbi::sim::Parameters prm;
  prm.newton_iterations = 30;
  prm.newton_tolerance = 1e-9;
  mbi::sim::Simulator sim(cage.U, cage.T, mbi::sim::Material{1e6, 0.3, 1000}, prm);
  sim.set_potential(contact);
  for (int step = 0; step < 120; ++step) {
    const auto r = sim.step();
    REQUIRE(r.success);
  }
  Eigen::VectorXd x(3 * cage.U.rows());
  for (Eigen::Index i = 0; i < cage.U.rows(); ++i) x.segment<3>(3 * i) = sim.positions().row(i).transpose();
  const Eigen::MatrixXd p = contact->points(x);
  const double diagonal = std::sqrt(3.0);
  // Weight 9810 N on 25 points at 1e7 N/m: about 4e-5 m of penetration each.
  CHECK(p.col(1).minCoeff() - floor >= -1e-3 * diagonal);
  CHECK(p.col(1).maxCoeff() - floor <= 1e-3 * diagonal);
  CHECK(sim.positions().col(1).minCoeff() < floor - 0.02);  // the cage's bottom went below the floor
  CHECK(contact->time() == Approx(sim.time()));  // posed at the end of the last substep
}
