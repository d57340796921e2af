// Contact at embedded points through the embedding's transpose (method.md facts 16 and 17).
#include <mbi/error.hpp>
#include <mbi/pipeline/contact_laws.hpp>
#include <mbi/pipeline/mesh_level_set.hpp>
#include <mbi/pipeline/surface_contact.hpp>

#include <catch2/catch.hpp>
#include "common/grid_meshes.hpp"
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <limits>
#include <memory>
#include <optional>
#include <random>

using namespace mbi::pipeline;

namespace {

// The pose is the rest box moved by kShift into the colliders (which stay clear of the rest box).
const Eigen::Vector3d kShift(0, -10, 0);

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
    for (int c = 0; c < 3; ++c) s.x(3 * i + c) = s.mesh.U(i, c) + kShift(c) + w(rng);
  return s;
}

std::vector<Collider> colliders() {
  return {Collider::plane(Eigen::Vector3d(0, 0.3, 0) + kShift, {0.1, 1.0, 0.05}, 0.5),
          Collider::sphere(Eigen::Vector3d(1.5, 1.0, 0.5) + kShift, 0.45, 0.3)};
}

/// The same contact with lagged friction: guards and slips from the pose x0 over a substep of
/// h = 0.01 s, the plane sliding by (3, 0, 1) mm in it, some points deeper than max_depth 0.2.
void start_friction(SurfaceContact& c, const Eigen::VectorXd& x0) {
  c.set_max_depth(0.2);
  c.set_friction_velocity(0.3);  // eps = 3 mm, about the slips' size: both regimes of f0
  c.begin_substep_at(0.0, 0.01, x0, Eigen::VectorXd::Zero(x0.size()));
}

std::vector<Collider> sliding_colliders() {
  auto c = colliders();
  c[0].motion.velocity = Eigen::Vector3d(0.3, 0, 0.1);
  return c;
}

/// x0 moved by a random 1 mm.
Eigen::VectorXd nudged(const Eigen::VectorXd& x0) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> w(-1e-3, 1e-3);
  Eigen::VectorXd x = x0;
  for (Eigen::Index k = 0; k < x.size(); ++k) x(k) += w(rng);
  return x;
}

/// For one method: a frictionless contact and one with lagged friction from s.x (contact, pose) pairs:
/// the first at s.x, the second at s.x nudged.
struct Contacts {
  std::shared_ptr<Deformer> deformer;
  std::unique_ptr<SurfaceContact> plain, lagged;
  std::vector<std::pair<SurfaceContact*, Eigen::VectorXd>> cases;
};

Contacts contacts(const Setup& s, Method m) {
  DeformerOptions opt;
  opt.method = m;
  Contacts c;
  c.deformer = std::make_shared<Deformer>(s.mesh.U, s.mesh.T, s.points, opt);
  c.plain = std::make_unique<SurfaceContact>(c.deformer, colliders(), 1e4);
  c.lagged = std::make_unique<SurfaceContact>(c.deformer, sliding_colliders(), 1e4);
  start_friction(*c.lagged, s.x);
  REQUIRE(c.lagged->friction_pairs() > 20);
  c.cases = {{c.plain.get(), s.x}, {c.lagged.get(), nudged(s.x)}};
  return c;
}

Eigen::VectorXd gradient(const SurfaceContact& c, const Eigen::VectorXd& x) {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  c.add_gradient(x, g);
  return g;
}

// Central differences (step 1e-7) of the contact's gradient: its Hessian, column by column.
Eigen::MatrixXd gradient_differences(const SurfaceContact& c, const Eigen::VectorXd& x) {
  const Eigen::Index N = x.size();
  Eigen::MatrixXd fd(N, N);
  for (Eigen::Index k = 0; k < N; ++k) {
    Eigen::VectorXd xp = x, xm = x;
    xp(k) += 1e-7;
    xm(k) -= 1e-7;
    fd.col(k) = (gradient(c, xp) - gradient(c, xm)) / 2e-7;
  }
  return fd;
}

}  // namespace

TEST_CASE("surface contact: force = finite differences of the energy through the pipeline, "
          "BI, Phong and modified-BI", "[pipeline][contact]") {
  const Setup s = setup();
  for (Method m : {Method::BI, Method::Phong, Method::ModifiedBI}) {
    const Contacts both = contacts(s, m);
    for (const auto& [contact, x] : both.cases) {
      const Eigen::VectorXd g = gradient(*contact, x);
      REQUIRE(contact->energy(x) > 0);
      Eigen::VectorXd fd(x.size());
      const double eps = 1e-6;
      for (Eigen::Index k = 0; k < x.size(); ++k) {
        Eigen::VectorXd xp = x, xm = x;
        xp(k) += eps;
        xm(k) -= eps;
        fd(k) = (contact->energy(xp) - contact->energy(xm)) / (2 * eps);
      }
      INFO("method " << static_cast<int>(m) << (contact == both.lagged.get() ? ", guarded, friction" : ", plain"));
      CHECK((fd - g).norm() <= 1e-6 * g.norm());
    }
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
      const Distance d = signed_distance(c, P.row(p).transpose(), 0.0);  // a plain penalty
      if (d.value >= 0) continue;
      ++touching;
      for (int a = 0; a < 4; ++a)
        expect.segment<3>(3 * s.mesh.T(emb.element(p), a)) += emb.bary(p, a) * 1e4 * d.value * d.normal;
    }
  CHECK(touching > 20);
  CHECK((gradient(contact, s.x) - expect).norm() <= 1e-12 * expect.norm());

  // Guarded law and lagged friction, from the laws alone: g_p = e'(d) n + mu lambda f1(y) / y
  // (I - n0 n0^T)(p - anchor), lambda = -e'(d0) at the start pose, the anchor moved with the plane.
  SurfaceContact lagged(deformer, sliding_colliders(), 1e4);
  start_friction(lagged, s.x);
  const Eigen::VectorXd x1 = nudged(s.x);
  const Eigen::MatrixXd P0 = lagged.points(s.x), P1 = lagged.points(x1);
  const double eps = 0.3 * 0.01;
  expect.setZero();
  int guarded = 0, slipping = 0, sticking = 0;
  for (Eigen::Index p = 0; p < P1.rows(); ++p)
    for (const Collider& c : lagged.colliders()) {
      const Eigen::Vector3d q0 = P0.row(p).transpose(), q1 = P1.row(p).transpose();
      const Distance d0 = signed_distance(c, q0, 0.01), d1 = signed_distance(c, q1, 0.01);
      const double depth = d0.value > -0.2 ? 0.2 : std::numeric_limits<double>::infinity();
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      if (d1.value < 0) g += mbi::pipeline::contact::normal_energy(d1.value, 1e4, depth).slope * d1.normal;
      if (d0.value < 0) {
        guarded += depth == 0.2;
        const double weight = -c.friction * mbi::pipeline::contact::normal_energy(d0.value, 1e4, depth).slope;
        const Eigen::Vector3d anchor = q0 + c.motion.velocity * 0.01;
        const Eigen::Vector3d u = (Eigen::Matrix3d::Identity() - d0.normal * d0.normal.transpose()) * (q1 - anchor);
        const double y = u.norm();
        (y < eps ? sticking : slipping) += 1;
        g += weight * (y < eps ? 2 / eps - y / (eps * eps) : 1 / y) * u;
      }
      for (int a = 0; a < 4; ++a) expect.segment<3>(3 * s.mesh.T(emb.element(p), a)) += emb.bary(p, a) * g;
    }
  CHECK(guarded > 10);
  CHECK(sticking > 5);
  CHECK(slipping > 5);
  CHECK((gradient(lagged, x1) - expect).norm() <= 1e-12 * expect.norm());
}

TEST_CASE("surface contact: energy along a line is the energy at x + s dx, BI, Phong and "
          "modified-BI, with friction", "[pipeline][contact]") {
  const Setup s = setup();
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> w(-0.02, 0.02);
  Eigen::VectorXd dx(s.x.size());  // a random move that also pushes the box 0.15 into the plane
  for (Eigen::Index k = 0; k < dx.size(); ++k) dx(k) = w(rng) + (k % 3 == 1 ? -0.15 : 0.0);
  for (Method m : {Method::BI, Method::Phong, Method::ModifiedBI}) {
    const Contacts both = contacts(s, m);
    for (const auto& [contact, x] : both.cases) {
      // points that start clear and touch further along: a line search that skipped them would differ
      const auto touching = [&](const Eigen::VectorXd& at) {
        const Eigen::MatrixXd P = contact->points(at);
        int count = 0;
        for (Eigen::Index p = 0; p < P.rows(); ++p)
          count += signed_distance(contact->colliders()[0], P.row(p).transpose(), contact->time()).value < 0;
        return count;
      };
      REQUIRE(touching(x + dx) > touching(x) + 20);
      contact->begin_line(x, dx);
      for (double t : {1.0, 0.5, 0.25, 0.125, 1.0 / 1024, 0.0, 1.5, -0.3}) {
        const double along = contact->energy_along(t);  // after energy() at another x: still this line
        const double direct = contact->energy(x + t * dx);
        INFO("method " << static_cast<int>(m) << (contact == both.lagged.get() ? ", friction" : ", plain") << ", s = " << t);
        REQUIRE(direct > 0);
        CHECK(std::abs(along - direct) <= 1e-12 * direct);
      }
    }
    const Eigen::VectorXd& x1 = both.cases[1].second;
    both.lagged->begin_substep_at(0.01, 0.02, x1, Eigen::VectorXd::Zero(x1.size()));
    CHECK_THROWS_WITH(both.lagged->energy_along(0.5), Catch::Contains("begin_line"));
  }
}

TEST_CASE("surface contact: after end_line the next evaluation, at the move's end, is a fresh "
          "contact's to round-off, BI, Phong and modified-BI, with friction", "[pipeline][contact]") {
  const Setup s = setup();
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> w(-0.02, 0.02);
  Eigen::VectorXd dx(s.x.size());
  for (Eigen::Index k = 0; k < dx.size(); ++k) dx(k) = w(rng) + (k % 3 == 1 ? -0.15 : 0.0);
  for (Method m : {Method::BI, Method::Phong, Method::ModifiedBI}) {
    const Contacts moved = contacts(s, m), fresh = contacts(s, m);
    for (size_t k = 0; k < moved.cases.size(); ++k) {
      SurfaceContact& c = *moved.cases[k].first;
      const Eigen::VectorXd& x = moved.cases[k].second;
      const double t = 0.375;
      const Eigen::VectorXd end = x + t * dx;  // the simulator's own sum: not x + t dx to the bit
      c.energy(x);
      const long long line0 = c.counts().move_candidates;
      c.begin_line(x, dx);
      c.energy_along(t);
      c.end_line(t);
      const long long line = c.counts().move_candidates - line0, evaluated = c.counts().candidates;
      const double E = c.energy(end);
      CHECK(c.counts().candidates - evaluated == line);  // the line's candidates, kept
      const SurfaceContact& f = *fresh.cases[k].first;
      INFO("method " << static_cast<int>(m) << (k == 1 ? ", friction" : ", plain"));
      const double want = f.energy(end);
      REQUIRE(want > 0);
      CHECK(std::abs(E - want) <= 1e-12 * want);
      const Eigen::VectorXd g = gradient(c, end), gf = gradient(f, end);
      CHECK((g - gf).norm() <= 1e-11 * gf.norm());
      // elsewhere than the move's end: evaluated afresh
      c.begin_line(x, dx);
      c.energy_along(t);
      c.end_line(t);
      CHECK(std::abs(c.energy(x) - f.energy(x)) <= 1e-12 * f.energy(x));
    }
  }
}

TEST_CASE("surface contact: a new time or law is seen at the same positions", "[pipeline][contact]") {
  const Setup s = setup();
  auto deformer = std::make_shared<Deformer>(s.mesh.U, s.mesh.T, s.points);
  SurfaceContact kept(deformer, sliding_colliders(), 1e4);
  const double before = kept.energy(s.x);
  const Eigen::VectorXd g_before = gradient(kept, s.x);
  kept.set_time(0.5);
  SurfaceContact fresh(deformer, sliding_colliders(), 1e4);
  fresh.set_time(0.5);
  CHECK(kept.energy(s.x) == fresh.energy(s.x));
  CHECK(kept.energy(s.x) != before);
  CHECK(gradient(kept, s.x) == gradient(fresh, s.x));
  CHECK(gradient(kept, s.x) != g_before);
  start_friction(kept, s.x);  // guards and slips at the positions of the evaluation before
  start_friction(fresh, s.x);
  CHECK(kept.energy(s.x) == fresh.energy(s.x));
  const Eigen::VectorXd x1 = nudged(s.x);
  CHECK(kept.energy(x1) == fresh.energy(x1));
  CHECK(gradient(kept, x1) == gradient(fresh, x1));
}

TEST_CASE("surface contact: the Hessian surrogate is PSD, inside the element pattern, and equals "
          "W^T K W for BI", "[pipeline][contact]") {
  const Setup s = setup();
  for (Method m : {Method::BI, Method::ModifiedBI}) {
    DeformerOptions opt;
    opt.method = m;
    auto deformer = std::make_shared<Deformer>(s.mesh.U, s.mesh.T, s.points, opt);
    SurfaceContact contact(deformer, sliding_colliders(), 1e4);
    start_friction(contact, s.x);
    std::vector<mbi::sim::NodeBlock> blocks;
    contact.hessian_blocks(nudged(s.x), blocks);
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
      const Eigen::MatrixXd fdf = gradient_differences(flat, s.x);
      CHECK(Hf.norm() > 0);
      CHECK((fdf - Hf).norm() <= 1e-5 * Hf.norm());
    }
  }
}

TEST_CASE("surface contact: the Hessian product is W^T K W (finite differences of the force against "
          "a plane) for Phong and modified-BI, symmetric PSD with friction, and none for BI",
          "[pipeline][contact]") {
  const Setup s = setup();
  const Eigen::Index N = s.x.size();
  auto product_matrix = [&](const SurfaceContact& c, const Eigen::VectorXd& x) {
    Eigen::MatrixXd H(N, N);
    for (Eigen::Index k = 0; k < N; ++k) {
      Eigen::VectorXd col = Eigen::VectorXd::Zero(N);
      REQUIRE(c.add_hessian_product(x, Eigen::VectorXd::Unit(N, k), col));
      H.col(k) = col;
    }
    return H;
  };
  for (Method m : {Method::Phong, Method::ModifiedBI}) {
    DeformerOptions opt;
    opt.method = m;
    auto deformer = std::make_shared<Deformer>(s.mesh.U, s.mesh.T, s.points, opt);
    SurfaceContact flat(deformer, {colliders()[0]}, 1e4);
    const Eigen::MatrixXd H = product_matrix(flat, s.x);
    const Eigen::MatrixXd fd = gradient_differences(flat, s.x);
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(N, N);
    CHECK(H.norm() > 0);
    CHECK((fd - H).norm() <= 1e-5 * H.norm());
    std::vector<mbi::sim::NodeBlock> blocks;
    flat.hessian_blocks(s.x, blocks);
    for (const auto& b : blocks) {
      S.block<3, 3>(3 * b.row, 3 * b.col) += b.value;
      if (b.row != b.col) S.block<3, 3>(3 * b.col, 3 * b.row) += b.value.transpose();
    }
    CHECK((S - H).norm() >= 0.01 * H.norm());  // the blocks are only a surrogate here
    SurfaceContact lagged(deformer, sliding_colliders(), 1e4);
    start_friction(lagged, s.x);
    const Eigen::MatrixXd L = product_matrix(lagged, nudged(s.x));
    CHECK((L - L.transpose()).norm() <= 1e-12 * L.norm());
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (L + L.transpose()));
    CHECK(eig.eigenvalues().minCoeff() >= -1e-9 * eig.eigenvalues().maxCoeff());
  }
  DeformerOptions bi_options;
  bi_options.method = Method::BI;
  auto bi = std::make_shared<Deformer>(s.mesh.U, s.mesh.T, s.points, bi_options);
  SurfaceContact contact(bi, colliders(), 1e4);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(N);
  CHECK_FALSE(contact.add_hessian_product(s.x, Eigen::VectorXd::Ones(N), out));
  CHECK(out.isZero(0));
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
  CHECK_THROWS_WITH(ok.begin_substep_at(nan, 1.0, s.x, s.x), Catch::Contains("time must be finite"));
  CHECK_THROWS_WITH(ok.begin_substep_at(0.0, 0.01, s.x, Eigen::VectorXd::Zero(3)),
                    Catch::Contains("contact: node velocities must have " + std::to_string(s.x.size()) + " entries, got 3"));
  bad = colliders();
  bad[0].friction = -0.1;
  CHECK_THROWS_WITH(SurfaceContact(deformer, bad, 1e4), Catch::StartsWith("collider 0: friction must be finite and >= 0"));
  for (double v : {nan, 0.0, -1.0}) {
    CHECK_THROWS_WITH(ok.set_max_depth(v), Catch::Contains("max_depth must be > 0"));
    CHECK_THROWS_WITH(ok.set_friction_velocity(v), Catch::Contains("friction velocity must be finite and > 0"));
  }
  CHECK_THROWS_WITH(ok.set_friction_velocity(std::numeric_limits<double>::infinity()),
                    Catch::Contains("friction velocity"));
  ok.set_max_depth(std::numeric_limits<double>::infinity());  // the plain penalty
  CHECK(ok.max_step(s.x, s.x) == 1.0);
  // A collider through the rest pose: the plane y = 0.3 cuts the box [0, 1.5] x [0, 1] x [0, 1].
  bad = {Collider::sphere({5, 5, 5}, 1.0), Collider::plane({0, 0.3, 0}, {0, 1, 0})};
  CHECK_THROWS_WITH(SurfaceContact(deformer, bad, 1e4),
                    Catch::StartsWith("collider 1 overlaps the model at rest: contact point") &&
                        Catch::Contains("m inside (at most"));
  bad[1].point.y() = -1e-4;  // touching within max_depth is contact, not overlap
  CHECK_NOTHROW(SurfaceContact(deformer, bad, 1e4));
}

TEST_CASE("surface contact: a moving collider that jumps into the model (its motion started "
          "before the contact was attached) pushes it out, every step finite",
          "[pipeline][contact][sim][errors]") {
  const auto cage = mbi::test::box_tet_mesh(2, 2, 2);
  Eigen::MatrixXd P(50, 3);
  for (int i = 0; i < 5; ++i)
    for (int k = 0; k < 5; ++k)
      for (int top = 0; top < 2; ++top)
        P.row(10 * i + 2 * k + top) = Eigen::RowVector3d(0.1 + 0.2 * i, top ? 0.9 : 0.1, 0.1 + 0.2 * k);
  DeformerOptions opt;
  opt.method = Method::BI;
  auto deformer = std::make_shared<Deformer>(cage.U, cage.T, P, opt);
  // The floor rises at 1 m/s (and slides at 2 m/s) from t = 0 to 0.35 s, from y = 0.
  Collider floor = Collider::plane({0, 0, 0}, {0, 1, 0}, 0.5);
  floor.motion.velocity = Eigen::Vector3d(2, 1, 0);
  floor.motion.stop = 0.35;
  auto contact = std::make_shared<SurfaceContact>(deformer, std::vector<Collider>{floor}, 1e7);
  mbi::sim::Parameters prm;
  prm.newton_iterations = 40;
  prm.newton_tolerance = 1e-7;
  prm.gravity.setZero();
  mbi::sim::Simulator sim(cage.U, cage.T, mbi::sim::Material{1e7, 0.3, 1000}, prm);
  for (int k = 0; k < 18; ++k) REQUIRE(sim.step().success);  // t = 0.3 s: the floor is 0.2 m into the model
  sim.set_potential(contact);
  prm.gravity = Eigen::Vector3d(0, -9.81, 0);
  sim.set_params(prm);
  double lowest = 1e300;  // gap to the floor after the first step
  for (int k = 0; k < 20; ++k) {
    const auto r = sim.step();
    INFO("step " << k << ": " << r.message);
    REQUIRE(r.success);
    REQUIRE(sim.positions().allFinite());
    REQUIRE(sim.velocities().allFinite());
    Eigen::VectorXd x(3 * sim.nodes());
    for (int i = 0; i < sim.nodes(); ++i) x.segment<3>(3 * i) = sim.positions().row(i).transpose();
    // While the floor rises 1.7 cm a step (more than max_depth) it overtakes points (documented);
    // once it has stopped at 0.35 m every point is guarded again.
    if (sim.time() > 0.35 + 1e-9) lowest = std::min(lowest, contact->points(x).col(1).minCoeff() - 0.35);
  }
  CHECK(lowest >= -contact->max_depth());
  CHECK(lowest < 1e299);
  // Time jumps back (reset): the floor is at y = 0 again, below the model at rest.
  sim.reset();
  for (int k = 0; k < 5; ++k) REQUIRE(sim.step().success);
  CHECK(sim.positions().allFinite());
}

TEST_CASE("surface contact: a cage dropped on a plane rests on its dense surface, not on the cage",
          "[pipeline][contact][sim][long]") {
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

namespace {

// The box [-half, half] as a mesh collider (12 triangles), or none in a build without OpenVDB.
std::optional<Collider> box_mesh_collider(const Eigen::Vector3d& half) {
  Eigen::MatrixXd V(8, 3);
  Eigen::MatrixXi F(12, 3);
  for (int i = 0; i < 8; ++i)
    V.row(i) << (i & 1 ? 1 : -1) * half.x(), (i & 2 ? 1 : -1) * half.y(), (i & 4 ? 1 : -1) * half.z();
  F << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5;
  try {
    return Collider::mesh(std::make_shared<const MeshLevelSet>(V, F));
  } catch (const mbi::Error&) {
    return std::nullopt;
  }
}

}  // namespace

namespace {

/// Energy, gradient and Hessian (dense, 3 n square) of the normal contact from every point
/// (no broad phase), from the laws alone; depth(p, c): the guarded depth of the pair.
struct Full {
  double energy = 0.0;
  Eigen::VectorXd gradient;
  Eigen::MatrixXd hessian;
  int touching = 0;
};

template <typename Depth>
Full full_contact(const Deformer& deformer, const SurfaceContact& contact, const Eigen::VectorXd& x, Depth depth) {
  const Eigen::MatrixXd P = contact.points(x);
  const mbi::interp::Embedding& emb = deformer.embedding();
  const Eigen::MatrixXi& T = deformer.elements_matrix();
  Full f;
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(P.rows(), 3);
  f.hessian.setZero(x.size(), x.size());
  for (Eigen::Index p = 0; p < P.rows(); ++p) {
    bool touching = false;
    for (size_t c = 0; c < contact.colliders().size(); ++c) {
      const Distance d = signed_distance(contact.colliders()[c], P.row(p).transpose(), contact.time());
      if (d.value >= 0) continue;
      touching = true;
      const contact::Law law = contact::normal_energy(d.value, contact.stiffness(), depth(p, c));
      f.energy += law.value;
      G.row(p) += law.slope * d.normal.transpose();
      const Eigen::Matrix3d K = law.curvature * d.normal * d.normal.transpose();
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          f.hessian.block<3, 3>(3 * T(emb.element(p), a), 3 * T(emb.element(p), b)) += emb.bary(p, a) * emb.bary(p, b) * K;
    }
    f.touching += touching;
  }
  const Eigen::MatrixXd GX = deformer.vjp(G);
  f.gradient.resize(x.size());
  for (Eigen::Index i = 0; i < GX.rows(); ++i) f.gradient.segment<3>(3 * i) = GX.row(i).transpose();
  return f;
}

Eigen::MatrixXd dense_hessian(const SurfaceContact& contact, const Eigen::VectorXd& x) {
  std::vector<mbi::sim::NodeBlock> blocks;
  contact.hessian_blocks(x, blocks);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(x.size(), x.size());
  for (const mbi::sim::NodeBlock& b : blocks) {
    H.block<3, 3>(3 * b.row, 3 * b.col) += b.value;
    if (b.row != b.col) H.block<3, 3>(3 * b.col, 3 * b.row) += b.value.transpose();
  }
  return H;
}

}  // namespace

TEST_CASE("surface contact: the points of elements far from every collider are skipped exactly, "
          "also when the collider moves into them", "[pipeline][contact]") {
  // A long bar whose bottom a ball dents, the ball rolling along it by a third of the bar per
  // substep: into elements that were far from it in the substep before; and a tilted plane
  // under its far end, which the move dx (0.1 down) brings into elements far from it at x.
  const mbi::test::Mesh mesh = mbi::test::box_tet_mesh(9, 2, 2, Eigen::Vector3d(3.0, 0.5, 0.5));
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0), w(-0.01, 0.01);
  Eigen::MatrixXd points(3000, 3);
  for (Eigen::Index p = 0; p < points.rows(); ++p) points.row(p) = Eigen::RowVector3d(3 * u(rng), 0.5 * u(rng), 0.5 * u(rng));
  Collider ball = Collider::sphere({-0.5, -0.78, 0.25}, 0.4);  // 0.12 into the bar's bottom
  ball.motion.velocity = Eigen::Vector3d(100, 0, 0);              // 1 m per substep of 0.01 s
  const Collider plane = Collider::plane({2.4, -0.5, 0}, {-0.1, 1, 0});   // 6 cm into the far end
  Eigen::VectorXd x0(3 * mesh.U.rows()), dx(x0.size());
  for (Eigen::Index i = 0; i < mesh.U.rows(); ++i)
    for (int c = 0; c < 3; ++c) {
      x0(3 * i + c) = mesh.U(i, c) + (c == 1 ? -0.5 : 0.0) + w(rng);
      dx(3 * i + c) = w(rng) + (c == 1 ? -0.1 : 0.0);
    }
  std::vector<Collider> colliders{ball, plane};
  if (const auto slab = box_mesh_collider({0.3, 0.1, 0.3})) {  // a build with OpenVDB: a mesh too
    colliders.push_back(*slab);
    colliders.back().point = Eigen::Vector3d(1.5, -0.58, 0.25);  // 2 cm into the bar's bottom
    colliders.back().motion.velocity = Eigen::Vector3d(0, 0, 5);  // 5 cm per substep
  }
  const double D = 0.02;  // some pairs start deeper: plain penalty for them
  for (Method m : {Method::BI, Method::Phong, Method::ModifiedBI}) {
    DeformerOptions opt;
    opt.method = m;
    auto deformer = std::make_shared<Deformer>(mesh.U, mesh.T, points, opt);
    SurfaceContact contact(deformer, colliders, 1e4);
    contact.set_max_depth(D);
    for (double t0 : {0.0, 0.01}) {
      INFO("method " << static_cast<int>(m) << ", substep from " << t0 << " s");
      contact.begin_substep_at(t0, t0 + 0.01, x0, Eigen::VectorXd::Zero(x0.size()));
      const Eigen::MatrixXd P0 = contact.points(x0);
      const auto depth = [&](Eigen::Index p, size_t c) {
        return signed_distance(contact.colliders()[c], P0.row(p).transpose(), contact.time()).value > -D
                   ? D : std::numeric_limits<double>::infinity();
      };
      contact.begin_line(x0, dx);
      for (double s : {0.0, 0.5, 1.0}) {
        const Eigen::VectorXd x = x0 + s * dx;
        const Full f = full_contact(*deformer, contact, x, depth);
        REQUIRE(f.touching > 20);
        REQUIRE(f.touching < 0.6 * points.rows());  // most points are far from the plane
        CHECK(contact.touching(x) == f.touching);
        CHECK(std::abs(contact.energy(x) - f.energy) <= 1e-12 * f.energy);
        CHECK((gradient(contact, x) - f.gradient).norm() <= 1e-12 * f.gradient.norm());
        CHECK((dense_hessian(contact, x) - f.hessian).norm() <= 1e-12 * f.hessian.norm());
        CHECK(std::abs(contact.energy_along(s) - f.energy) <= 1e-12 * f.energy);  // after energy() elsewhere
      }
      // The cap: every guarded point of every element, from the laws.
      const Eigen::MatrixXd P = contact.points(x0), Dp = contact.points(dx);
      double cap = 1.0;
      for (Eigen::Index p = 0; p < P.rows(); ++p)
        for (size_t c = 0; c < colliders.size(); ++c)
          if (!std::isinf(depth(p, c)))
            cap = std::min(cap, contact::advance(contact.colliders()[c], P.row(p).transpose(), Dp.row(p).transpose(),
                                                 contact.time(), D));
      CHECK(cap < 1.0);
      CHECK(std::abs(contact.max_step(x0, dx) - cap) <= 1e-12 * cap);
    }
  }
}

namespace {

/// n points spread evenly on the sphere of radius 1 about centre (a golden-angle spiral).
Eigen::MatrixXd sphere_points(int n, const Eigen::Vector3d& centre) {
  Eigen::MatrixXd P(n, 3);
  for (int i = 0; i < n; ++i) {
    const double y = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - y * y), phi = 2.399963229728653 * i;
    P.row(i) = (centre + Eigen::Vector3d(r * std::cos(phi), y, r * std::sin(phi))).transpose();
  }
  return P;
}

/// A ball of points in a 4^3-cell cage [0, 2.2]^3 over the plane y = 0.1 (touching it at rest),
/// with friction; x0: the cage moved 5 cm down into it (a cap of 2.5% of the ball's surface).
struct Ball {
  mbi::test::Mesh mesh = mbi::test::box_tet_mesh(4, 4, 4, Eigen::Vector3d::Constant(2.2));
  std::shared_ptr<Deformer> deformer;
  std::unique_ptr<SurfaceContact> contact;
  Eigen::VectorXd x0;
  explicit Ball(int points, Method method = Method::BI) {
    DeformerOptions opt;
    opt.method = method;
    deformer = std::make_shared<Deformer>(mesh.U, mesh.T, sphere_points(points, Eigen::Vector3d::Constant(1.1)), opt);
    Collider plane = Collider::plane({0, 0.1, 0}, {0, 1, 0}, 0.5);
    plane.motion.velocity = Eigen::Vector3d(0.2, 0, 0.1);  // sliding under the ball: lagged friction
    contact = std::make_unique<SurfaceContact>(deformer, std::vector<Collider>{plane}, 1e4);
    contact->set_max_depth(0.2);
    contact->set_friction_velocity(0.3);
    x0.resize(3 * mesh.U.rows());
    for (Eigen::Index i = 0; i < mesh.U.rows(); ++i) x0.segment<3>(3 * i) = mesh.U.row(i).transpose() - Eigen::Vector3d(0, 0.05, 0);
  }
};

/// Adds to f the lagged friction of a substep from the start positions x0 (times t0 to the
/// contact's time), from the laws alone: per point and collider inside at the start, mu lambda
/// f0(|u|) with u the slip projected on the tangent plane (f0 depends on |u| only).
template <typename Depth>
void add_friction(const Deformer& deformer, const SurfaceContact& contact, const Eigen::VectorXd& x0, double t0,
                  const Eigen::VectorXd& x, Depth depth, double eps, Full& f) {
  const Eigen::MatrixXd P0 = contact.points(x0), P = contact.points(x);
  const mbi::interp::Embedding& emb = deformer.embedding();
  const Eigen::MatrixXi& T = deformer.elements_matrix();
  const double t1 = contact.time();
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(P.rows(), 3);
  for (Eigen::Index p = 0; p < P.rows(); ++p)
    for (size_t c = 0; c < contact.colliders().size(); ++c) {
      const Collider& col = contact.colliders()[c];
      const Eigen::Vector3d q0 = P0.row(p).transpose();
      const Distance d = signed_distance(col, q0, t1);
      if (d.value >= 0 || col.friction == 0) continue;
      const double w = -col.friction * contact::normal_energy(d.value, contact.stiffness(), depth(p, c)).slope;
      Eigen::Matrix<double, 3, 2> B;
      B.col(0) = d.normal.unitOrthogonal();
      B.col(1) = d.normal.cross(B.col(0));
      const Eigen::Vector2d u = B.transpose() * (P.row(p).transpose() - q0 - collider_displacement(col, q0, t0, t1));
      f.energy += w * contact::friction_f0(u.norm(), eps);
      G.row(p) += (w * contact::friction_f1_over_y(u.norm(), eps) * (B * u)).transpose();
      const Eigen::Matrix3d K = B * (w * contact::friction_hessian(u, eps)) * B.transpose();
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          f.hessian.block<3, 3>(3 * T(emb.element(p), a), 3 * T(emb.element(p), b)) += emb.bary(p, a) * emb.bary(p, b) * K;
    }
  const Eigen::MatrixXd GX = deformer.vjp(G);
  for (Eigen::Index i = 0; i < GX.rows(); ++i) f.gradient.segment<3>(3 * i) += GX.row(i).transpose();
}

}  // namespace

TEST_CASE("surface contact: the broad phase's candidates give the contact of every point, with friction, "
          "over two substeps of Newton-like iterates", "[pipeline][contact]") {
  // A ball of points 5 cm into a sliding plane: the start, then moves (the cage sinking 4 mm
  // with a random 1 mm), one that lifts the ball 0.3 m off the plane (its friction points then lie in
  // elements far from the plane) and back, in two substeps, the second from 8 mm lower.
  for (Method m : {Method::BI, Method::ModifiedBI}) {
    Ball ball(3000, m);
    SurfaceContact& contact = *ball.contact;
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> w(-1e-3, 1e-3);
    Eigen::VectorXd sink(ball.x0.size()), lift = Eigen::VectorXd::Zero(ball.x0.size());
    for (Eigen::Index k = 0; k < sink.size(); ++k) sink(k) = w(rng) + (k % 3 == 1 ? -4e-3 : 0.0);
    for (Eigen::Index k = 1; k < lift.size(); k += 3) lift(k) = 0.3;
    Eigen::VectorXd start = ball.x0;
    for (double t0 : {0.0, 0.01}) {
      INFO("method " << static_cast<int>(m) << ", substep from " << t0 << " s");
      // the second substep's start velocity is 0: its start evaluates the points the first
      // substep's iterates brought near, the rest keep bounds carried from the first's start
      contact.begin_substep_at(t0, t0 + 0.01, start, (t0 == 0 ? 1.0 : 0.0) * sink / 0.01);
      REQUIRE(contact.friction_pairs() > 20);
      const Eigen::MatrixXd P0 = contact.points(start);
      const auto depth = [&](Eigen::Index p, size_t c) {
        return signed_distance(contact.colliders()[c], P0.row(p).transpose(), contact.time()).value > -0.2
                   ? 0.2 : std::numeric_limits<double>::infinity();
      };
      for (const Eigen::VectorXd& x : {Eigen::VectorXd(start), Eigen::VectorXd(start + sink),
                                       Eigen::VectorXd(start + 0.5 * sink + lift), Eigen::VectorXd(start + 2 * sink)}) {
        Full f = full_contact(*ball.deformer, contact, x, depth);
        add_friction(*ball.deformer, contact, start, t0, x, depth, 0.3 * 0.01, f);
        CHECK(contact.touching(x) == f.touching);
        CHECK(std::abs(contact.energy(x) - f.energy) <= 1e-12 * f.energy);
        CHECK((gradient(contact, x) - f.gradient).norm() <= 1e-12 * f.gradient.norm());
        CHECK((dense_hessian(contact, x) - f.hessian).norm() <= 1e-12 * f.hessian.norm());
      }
      // the line and the cap on the move start -> start + 2 sink
      contact.begin_line(start, 2 * sink);
      for (double s : {1.0, 0.5}) {
        Full f = full_contact(*ball.deformer, contact, start + 2 * s * sink, depth);
        add_friction(*ball.deformer, contact, start, t0, start + 2 * s * sink, depth, 0.3 * 0.01, f);
        CHECK(std::abs(contact.energy_along(s) - f.energy) <= 1e-12 * f.energy);
      }
      const Eigen::MatrixXd P = contact.points(start), D = contact.points(2 * sink) - contact.points(Eigen::VectorXd::Zero(sink.size()));
      double cap = 1.0;
      for (Eigen::Index p = 0; p < P.rows(); ++p)
        if (!std::isinf(depth(p, 0)))
          cap = std::min(cap, contact::advance(contact.colliders()[0], P.row(p).transpose(), D.row(p).transpose(), contact.time(), 0.2));
      CHECK(std::abs(contact.max_step(start, 2 * sink) - cap) <= 1e-12 * cap);
      start += 2 * sink;
    }
  }
}

TEST_CASE("surface contact: on a resting contact the candidates are at most twice the points with a term, "
          "and grow with them, at 3,000 and 12,000 points", "[pipeline][contact]") {
  // A Newton-like substep of the ball 5 cm into the plane: iterates 1 mm apart.
  std::vector<double> candidates;
  for (int points : {3000, 12000}) {
    Ball ball(points);
    SurfaceContact& contact = *ball.contact;
    std::mt19937 rng(37);
    std::uniform_real_distribution<double> w(-1e-3, 1e-3);
    Eigen::VectorXd step(ball.x0.size());
    for (Eigen::Index k = 0; k < step.size(); ++k) step(k) = w(rng);
    contact.begin_substep_at(0.0, 0.01, ball.x0, Eigen::VectorXd::Zero(ball.x0.size()));
    contact.reset_counts();
    Eigen::VectorXd x = ball.x0;
    for (int iteration = 0; iteration < 3; ++iteration, x += step) {
      contact.max_step(x, step);
      contact.begin_line(x, step);
      Eigen::VectorXd g = gradient(contact, x);
      (void)g;
    }
    const SurfaceContact::Counts& c = contact.counts();
    INFO(points << " points: " << c.candidates << " candidates, " << c.active << " with a term in "
                << c.evaluations << " evaluations; " << c.move_candidates << " candidates in " << c.moves << " moves");
    CHECK(c.evaluations == 3);
    CHECK(c.moves == 3);
    CHECK(c.active >= 3 * 0.02 * points);  // about 2.5% of the surface is inside the plane
    CHECK(c.candidates <= 2 * c.active);
    CHECK(c.move_candidates <= 2 * c.active);
    candidates.push_back(static_cast<double>(c.candidates));
  }
  CHECK(candidates[1] / candidates[0] == Approx(4).epsilon(0.15));  // linear in the points that touch
}
