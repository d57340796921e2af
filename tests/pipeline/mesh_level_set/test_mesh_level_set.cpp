// MeshLevelSet (docs/mesh-colliders.md): OpenVDB's level set of a closed triangle mesh against
// exact distances, its rigid motion, its outside value, threads and bad input.
#include <mbi/error.hpp>
#include <mbi/pipeline/colliders.hpp>
#include <mbi/pipeline/contact_laws.hpp>
#include <mbi/pipeline/mesh_level_set.hpp>
#include <mbi/sim/rigid_pose.hpp>

#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <random>
#include <thread>
#include <utility>
#include <vector>

using namespace mbi::pipeline;

namespace {

struct TriMesh {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
};

/// Icosahedron subdivided `levels` times, vertices on the sphere (centre, radius).
TriMesh icosphere(int levels, const Eigen::Vector3d& centre = Eigen::Vector3d::Zero(), double radius = 1.0) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      if (auto it = mid.find(key); it != mid.end()) return it->second;
      v.push_back((v[std::size_t(a)] + v[std::size_t(b)]).normalized());
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const auto& tri : f) {
      const int a = midpoint(tri(0), tri(1)), b = midpoint(tri(1), tri(2)), c = midpoint(tri(2), tri(0));
      next.insert(next.end(), {{tri(0), a, c}, {tri(1), b, a}, {tri(2), c, b}, {a, b, c}});
    }
    f = std::move(next);
  }
  TriMesh m{Eigen::MatrixXd(Eigen::Index(v.size()), 3), Eigen::MatrixXi(Eigen::Index(f.size()), 3)};
  for (std::size_t i = 0; i < v.size(); ++i) m.V.row(Eigen::Index(i)) = (centre + radius * v[i]).transpose();
  for (std::size_t i = 0; i < f.size(); ++i) m.F.row(Eigen::Index(i)) = f[i].transpose();
  return m;
}

/// The box [-half, half] as 12 triangles.
TriMesh box_mesh(const Eigen::Vector3d& half) {
  TriMesh m{Eigen::MatrixXd(8, 3), Eigen::MatrixXi(12, 3)};
  for (int i = 0; i < 8; ++i)
    m.V.row(i) << (i & 1 ? 1 : -1) * half.x(), (i & 2 ? 1 : -1) * half.y(), (i & 4 ? 1 : -1) * half.z();
  m.F << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5;
  return m;
}

double box_distance(const Eigen::Vector3d& half, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = p.cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

/// Points with |true distance| below `reach`, around a shape of the given size.
template <class Distance>
std::vector<Eigen::Vector3d> points_near(const Distance& distance, double size, double reach, int count) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-size, size);
  std::vector<Eigen::Vector3d> out;
  while (int(out.size()) < count) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    if (std::abs(distance(p)) < reach) out.push_back(p);
  }
  return out;
}

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / M_PI;
}

}  // namespace

TEST_CASE("mesh level set: an icosphere's distance is the sphere's within a voxel, normals within 6 degrees",
          "[pipeline][mesh_level_set]") {
  const TriMesh m = icosphere(3);  // 1280 triangles; flat faces sit at most 0.003 inside the sphere
  const MeshLevelSet ls(m.V, m.F);
  const double h = ls.voxel_size();
  CHECK(h == Approx(2 * std::sqrt(3.0) / 128).epsilon(1e-3));  // the default: the box's diagonal / 128
  CHECK(ls.voxel_size() == MeshLevelSet::default_voxel_size(m.V));
  CHECK(ls.band() == Approx(3 * h));
  const auto sphere = [](const Eigen::Vector3d& p) { return p.norm() - 1.0; };
  double worst = 0, worst_angle = 0;
  int inside = 0;
  for (const Eigen::Vector3d& p : points_near(sphere, 1.2, ls.band() - h, 2000)) {
    const LevelSetSample s = ls.sample(p);
    REQUIRE(s.in_band);
    worst = std::max(worst, std::abs(s.value - sphere(p)));
    worst_angle = std::max(worst_angle, angle_deg(s.normal, p));
    CHECK(s.normal.norm() == Approx(1.0));
    CHECK(s.gradient.norm() == Approx(1.0).margin(0.1));
    inside += sphere(p) < 0;
  }
  CHECK(inside > 500);
  CHECK(inside < 1500);
  CHECK(worst < h);
  CHECK(worst_angle < 6.0);
  // deep inside: the interior is resolved everywhere, the normal points out
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.5, 0.1, -0.2), Eigen::Vector3d(0.05, -0.3, 0.02)}) {
    const LevelSetSample s = ls.sample(p);
    CHECK(s.in_band);
    CHECK(std::abs(s.value - sphere(p)) < h);
    CHECK(angle_deg(s.normal, p) < 6.0);
  }
}

TEST_CASE("mesh level set: a box mesh's distance is the exact box distance within a voxel", "[pipeline][mesh_level_set]") {
  const Eigen::Vector3d half(0.5, 0.3, 0.2);
  const TriMesh m = box_mesh(half);
  const MeshLevelSet ls(m.V, m.F, {.voxel_size = 0.01, .band_voxels = 4});
  CHECK(ls.voxel_size() == 0.01);
  CHECK(ls.band() == Approx(0.04));
  CHECK(ls.bounds().min().isApprox(-half));
  CHECK(ls.active_voxels() > 100 * 60 * 40);  // the interior and the band
  const auto box = [&](const Eigen::Vector3d& p) { return box_distance(half, p); };
  double worst = 0;
  for (const Eigen::Vector3d& p : points_near(box, 0.6, ls.band() - 0.01, 2000)) {
    const LevelSetSample s = ls.sample(p);
    REQUIRE(s.in_band);
    worst = std::max(worst, std::abs(s.value - box(p)));
  }
  CHECK(worst < 0.01);
  // a face's normal away from its edges is the face's
  CHECK(angle_deg(ls.sample({0.1, 0.05, 0.21}).normal, Eigen::Vector3d::UnitZ()) < 1.0);
  CHECK(angle_deg(ls.sample({0.1, -0.31, 0.05}).normal, -Eigen::Vector3d::UnitY()) < 1.0);
}

TEST_CASE("mesh level set: sampled through a rigid motion, the mesh moves rigidly", "[pipeline][mesh_level_set]") {
  const Eigen::Vector3d half(0.5, 0.3, 0.2);
  const TriMesh m = box_mesh(half);
  const MeshLevelSet ls(m.V, m.F);
  mbi::sim::RigidMotion motion;
  motion.center = {0.3, -0.1, 0.2};
  motion.axis = Eigen::Vector3d(0.2, 1.0, 0.3).normalized();
  motion.angular_velocity = 1.3;
  motion.velocity = {0.4, -0.2, 0.1};
  motion.start = 0.25;
  const double t = 1.1, s = t - motion.start;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(motion.angular_velocity * s, motion.axis).toRotationMatrix();
  const auto to_world = [&](const Eigen::Vector3d& local) -> Eigen::Vector3d {
    return motion.center + motion.velocity * s + R * (local - motion.center);
  };
  const auto box = [&](const Eigen::Vector3d& p) { return box_distance(half, p); };
  for (const Eigen::Vector3d& local : points_near(box, 0.6, 0.03, 200)) {
    const LevelSetSample moved = ls.sample(to_world(local), motion, t);
    const LevelSetSample still = ls.sample(local);
    CHECK(moved.value == Approx(still.value).margin(1e-9));
    CHECK((moved.normal - R * still.normal).norm() < 1e-9);
    CHECK((moved.gradient - R * still.gradient).norm() < 1e-9);
  }
  // before the start the mesh is where it was given
  const Eigen::Vector3d p(0.55, 0.1, 0.0);
  CHECK(ls.sample(p, motion, 0.0).value == ls.sample(p).value);
  CHECK(ls.sample(p).value == Approx(0.05).margin(ls.voxel_size()));
}

TEST_CASE("mesh level set: outside the band, a conservative distance that points away", "[pipeline][mesh_level_set]") {
  const TriMesh m = icosphere(2);
  const MeshLevelSet ls(m.V, m.F);
  const LevelSetSample far = ls.sample({10, 0, 0});
  CHECK_FALSE(far.in_band);
  CHECK(far.value == Approx(9.0));  // the distance to the bounding box
  CHECK(far.value <= 9.0);
  CHECK(far.normal.isApprox(Eigen::Vector3d::UnitX()));
  // just beyond the band, inside the bounding box (a corner): the band width, a lower bound
  const Eigen::Vector3d corner = Eigen::Vector3d::Constant(0.9);
  const LevelSetSample c = ls.sample(corner);
  CHECK_FALSE(c.in_band);
  CHECK(c.value == Approx(ls.band()));
  CHECK(c.value <= corner.norm() - 1.0);
  CHECK(c.gradient.isZero());
  CHECK(angle_deg(c.normal, corner) < 1e-6);
  // every sample is a lower bound of the distance within a voxel, near or far
  for (const Eigen::Vector3d& p : points_near([](const Eigen::Vector3d& q) { return q.norm() - 1.0; }, 3.0, 10.0, 500))
    CHECK(ls.sample(p).value <= p.norm() - 1.0 + ls.voxel_size());
}

TEST_CASE("mesh level set: sign by reachability: orientation ignored, overlapping parts give their union",
          "[pipeline][mesh_level_set]") {
  const TriMesh a = icosphere(2), b = icosphere(2, {0.8, 0, 0});
  TriMesh both{Eigen::MatrixXd(a.V.rows() + b.V.rows(), 3), Eigen::MatrixXi(a.F.rows() + b.F.rows(), 3)};
  both.V << a.V, b.V;
  both.F << a.F, b.F.array() + int(a.V.rows());
  for (Eigen::Index t = 0; t < a.F.rows(); t += 2) std::swap(both.F(t, 0), both.F(t, 1));  // flip half of a
  const MeshLevelSet ls(both.V, both.F, {.voxel_size = 0.03});
  const auto u = [](const Eigen::Vector3d& p) { return std::min(p.norm(), (p - Eigen::Vector3d(0.8, 0, 0)).norm()) - 1.0; };
  for (const Eigen::Vector3d& p : points_near(u, 2.0, 0.06, 500)) {
    if (u(p) > 0) CHECK(std::abs(ls.sample(p).value - u(p)) < 0.03 + 0.01);  // + the faces' sag
  }
  // inside both (the overlap) is inside; the surfaces of one inside the other are not
  CHECK(ls.sample({0.4, 0, 0}).value < -0.5);
  CHECK(ls.sample({0.95, 0.2, 0}).value < -0.5);
}

TEST_CASE("mesh level set: threads sampling at once get the values of one thread", "[pipeline][mesh_level_set]") {
  const TriMesh m = icosphere(2);
  const MeshLevelSet ls(m.V, m.F);
  const auto points = points_near([](const Eigen::Vector3d& p) { return p.norm() - 1.0; }, 1.3, 0.3, 4000);
  std::vector<LevelSetSample> serial;
  for (const auto& p : points) serial.push_back(ls.sample(p));
  std::vector<std::vector<LevelSetSample>> results(4);
  std::vector<std::thread> threads;
  const MeshLevelSet copy = ls;  // copies share the grid
  for (int k = 0; k < 4; ++k)
    threads.emplace_back([&, k] {
      const MeshLevelSet& use = k % 2 ? copy : ls;
      for (int r = 0; r < 3; ++r)
        for (const auto& p : points) results[std::size_t(k)].push_back(use.sample(p));
    });
  for (auto& th : threads) th.join();
  for (const auto& res : results) {
    REQUIRE(res.size() == 3 * serial.size());
    for (std::size_t i = 0; i < res.size(); ++i) {
      const LevelSetSample& x = res[i];
      const LevelSetSample& y = serial[i % serial.size()];
      REQUIRE(x.value == y.value);
      REQUIRE(x.gradient == y.gradient);
    }
  }
}

TEST_CASE("mesh level set: bad input is an Error naming the argument and the element", "[pipeline][mesh_level_set][errors]") {
  using Catch::Matchers::Contains;
  const TriMesh m = icosphere(1);
  // a hole: the last triangle removed leaves its three edges open
  const Eigen::MatrixXi open = m.F.topRows(m.F.rows() - 1);
  const Eigen::Vector3i last = m.F.row(m.F.rows() - 1).transpose();
  CHECK_THROWS_WITH(MeshLevelSet(m.V, open), Contains("not closed: 3 boundary edges") && Contains("triangles"));
  try {
    MeshLevelSet(m.V, open);
  } catch (const mbi::Error& e) {
    // the first open edge met is an edge of the removed triangle
    const std::string what = e.what();
    bool named = false;
    for (int k = 0; k < 3; ++k) {
      const int a = last(k), b = last((k + 1) % 3);
      named |= what.find("(" + std::to_string(b) + ", " + std::to_string(a) + ")") != std::string::npos;
    }
    CHECK(named);
  }
  Eigen::MatrixXi out = m.F;
  out(7, 2) = int(m.V.rows());
  CHECK_THROWS_WITH(MeshLevelSet(m.V, out), Contains("triangle 7 has vertex index " + std::to_string(m.V.rows()) + " out of range"));
  out(7, 2) = -1;
  CHECK_THROWS_WITH(MeshLevelSet(m.V, out), Contains("triangle 7 has vertex index -1"));
  Eigen::MatrixXi repeat = m.F;
  repeat(3, 1) = repeat(3, 0);
  CHECK_THROWS_WITH(MeshLevelSet(m.V, repeat), Contains("triangle 3 repeats vertex"));
  Eigen::MatrixXd nan = m.V;
  nan(5, 1) = std::nan("");
  CHECK_THROWS_WITH(MeshLevelSet(nan, m.F), Contains("vertices: vertex 5 is not finite"));
  CHECK_THROWS_WITH(MeshLevelSet(Eigen::MatrixXd(0, 3), m.F), Contains("vertices is empty"));
  CHECK_THROWS_WITH(MeshLevelSet(m.V, Eigen::MatrixXi(0, 3)), Contains("triangles is empty"));
  CHECK_THROWS_WITH(MeshLevelSet(m.V.leftCols(2), m.F), Contains("vertices must be n x 3"));
  CHECK_THROWS_WITH(MeshLevelSet(m.V, m.F.leftCols(2)), Contains("triangles must be m x 3"));
  CHECK_THROWS_WITH(MeshLevelSet(m.V, m.F, {.voxel_size = 0.0}), Contains("voxel_size must be finite and > 0"));
  CHECK_THROWS_WITH(MeshLevelSet(m.V, m.F, {.voxel_size = 1e-4}), Contains("too small for the mesh"));
  CHECK_THROWS_WITH(MeshLevelSet(m.V, m.F, {.voxel_size = {}, .band_voxels = 0.5}), Contains("band_voxels must be finite and >= 1"));
  const MeshLevelSet ls(m.V, m.F);
  CHECK_THROWS_WITH(ls.sample(Eigen::Vector3d(0, std::nan(""), 0)), Contains("the point is not finite"));
  CHECK_THROWS_WITH(ls.sample(Eigen::Vector3d::Zero(), mbi::sim::RigidMotion{}, std::nan("")),
                    Contains("the point or the time is not finite"));
}

TEST_CASE("mesh level set: the value changes by at most lipschitz() times the step, the gradient is no longer",
          "[pipeline][mesh_level_set]") {
  const TriMesh m = icosphere(3, Eigen::Vector3d(0.1, -0.2, 0.3), 0.8);
  const MeshLevelSet s(m.V, m.F);
  const double L = s.lipschitz();
  CHECK(L >= 1.0);
  CHECK(L < 2.0);  // a few voxels' worth of error in OpenVDB's distances, not a broken bound
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  double steepest = 0;
  for (int k = 0; k < 20000; ++k) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const Eigen::Vector3d q = p + 0.3 * s.voxel_size() * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const LevelSetSample a = s.sample(p), b = s.sample(q);
    steepest = std::max(steepest, a.gradient.norm());
    REQUIRE(a.gradient.norm() <= L * (1 + 1e-12));
    REQUIRE(std::abs(b.value - a.value) <= L * (q - p).norm() * (1 + 1e-9) + 1e-12);
  }
  CHECK(steepest > 1.0);  // the bound is needed: the interpolant is steeper than 1 somewhere
}

TEST_CASE("mesh collider: a box mesh placed and moved measures as the analytic box within a voxel",
          "[pipeline][mesh_level_set][colliders]") {
  const Eigen::Vector3d half(0.4, 0.25, 0.3);
  const TriMesh m = box_mesh(half);
  auto level_set = std::make_shared<const MeshLevelSet>(m.V, m.F);
  Collider mesh = Collider::mesh(level_set, 0.3);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  mesh.point = Eigen::Vector3d(0.5, -1, 2);
  mesh.axes = R;
  Collider box = Collider::box(mesh.point, half, R, 0.3);
  for (Collider* c : {&mesh, &box}) {
    c->motion = mbi::sim::RigidMotion{.center = Eigen::Vector3d(0, 0, 1), .axis = Eigen::Vector3d::UnitY(),
                                      .angular_velocity = 0.5, .velocity = Eigen::Vector3d(0.2, 0, -0.1)};
    REQUIRE_NOTHROW(check_collider(*c, "collider"));
  }
  CHECK(distance_lipschitz(mesh) == level_set->lipschitz());
  CHECK(distance_lipschitz(box) == 1.0);
  const double h = level_set->voxel_size();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  int near = 0;
  for (int k = 0; k < 6000; ++k) {
    const double t = 0.1 * (k % 7);
    const Eigen::Vector3d rest = mesh.point + R * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Vector3d p = mbi::sim::rigid_pose(box.motion, t).apply(rest, box.motion.center);
    const Distance a = signed_distance(mesh, p, t), b = signed_distance(box, p, t);
    if (b.value > level_set->band()) continue;  // resolved: the band outside, all of the inside
    ++near;
    REQUIRE(std::abs(a.value - b.value) < h);
    const Distance ap = signed_distance(posed(mesh, t), p, 0.0);  // posed: the same, static
    REQUIRE(std::abs(ap.value - a.value) < 1e-9);
  }
  CHECK(near > 1000);
}

TEST_CASE("mesh collider: conservative advancement toward a mesh never passes the depth",
          "[pipeline][mesh_level_set][colliders]") {
  const TriMesh m = icosphere(3);
  const Collider ball = Collider::mesh(std::make_shared<const MeshLevelSet>(m.V, m.F));
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  const double depth = 0.02;
  for (int k = 0; k < 500; ++k) {
    const Eigen::Vector3d dir = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const Eigen::Vector3d p = (1.05 + 0.3 * std::abs(u(rng))) * dir;
    const Eigen::Vector3d dp = -2.5 * dir + 0.3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const double s = contact::advance(ball, p, dp, 0.0, depth);
    const double room0 = signed_distance(ball, p, 0.0).value + depth;
    for (int j = 0; j <= 200; ++j)  // every point of the allowed segment keeps a tenth of its room
      REQUIRE(signed_distance(ball, p + s * j / 200.0 * dp, 0.0).value + depth >= 0.1 * room0 - 1e-12);
    CHECK(s < 1.0);
  }
}

TEST_CASE("mesh collider: without a level set it is an Error naming the collider", "[pipeline][mesh_level_set][colliders]") {
  Collider c = Collider::mesh(nullptr);
  CHECK_THROWS_WITH(check_collider(c, "colliders[2]"), Catch::Contains("colliders[2]") && Catch::Contains("level set"));
}
