// Colliders under the mouse: their meshes lie on the colliders' surfaces at their pose, normals
// outward; a ray picks the nearest collider but never a plane; a drag carries a collider by the
// displacement within dt at constant velocity (what contact sees), or at once when paused.
#include <catch2/catch.hpp>

#include <mbi/interact/collider.hpp>
#include <mbi/interact/error.hpp>

#include "common/skip.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <memory>
#include <optional>
#include <vector>

using namespace mbi::interact;
using mbi::pipeline::Collider;

namespace {

std::vector<Collider> shapes() {
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Collider moving = Collider::sphere({0, 1, 0}, 0.25);
  moving.motion.velocity = {1, 0, 0};
  moving.motion.start = 0.5;
  return {Collider::sphere({0.3, -0.2, 1}, 0.4), Collider::capsule({0, 0, 0}, {1, 2, 0.5}, 0.3),
          Collider::box({1, 0, -1}, {0.2, 0.5, 0.8}, turn), Collider::plane({0, -1, 0}, {0, 2, 1}), moving};
}

}  // namespace

TEST_CASE("collider meshes lie on the collider's surface at its pose, each triangle facing out", "[interact][collider]") {
  for (const Collider& c : shapes())
    for (double time : {0.0, 1.5}) {
      const ColliderMesh m = collider_mesh(c, time, {.plane_half = 3, .plane_center = {1, 1, 1}});
      REQUIRE(m.V.rows() == m.N.rows());
      REQUIRE(m.F.rows() > 0);
      REQUIRE(m.F.maxCoeff() < m.V.rows());
      for (Eigen::Index v = 0; v < m.V.rows(); ++v) {
        const mbi::pipeline::Distance d = mbi::pipeline::signed_distance(c, m.V.row(v).transpose(), time);
        CHECK(std::abs(d.value) < 1e-9);
        CHECK(m.N.row(v).norm() == Approx(1));
        if (c.shape != mbi::pipeline::ColliderShape::Box)  // a box's edges have many normals
          CHECK(m.N.row(v).dot(d.normal) == Approx(1).margin(1e-9));
      }
      for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
        const Eigen::Vector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), e = m.V.row(m.F(f, 2));
        const Eigen::Vector3d n = (b - a).cross(e - a);
        if (n.norm() < 1e-12) continue;  // the rings at the poles
        const Eigen::Vector3d mid = (a + b + e) / 3;
        // out of the solid: the distance grows along the winding's normal
        CHECK(mbi::pipeline::signed_distance(c, mid + 1e-4 * n.normalized(), time).value >
              mbi::pipeline::signed_distance(c, mid, time).value);
      }
    }
  const ColliderMesh plane = collider_mesh(Collider::plane({0, 2, 0}, {0, 1, 0}), 0, {.plane_half = 5, .plane_center = {1, 7, 1}});
  CHECK((plane.V.colwise().mean().transpose() - Eigen::Vector3d(1, 2, 1)).norm() < 1e-12);
  CHECK((plane.V.colwise().maxCoeff() - plane.V.colwise().minCoeff()).maxCoeff() == Approx(10));
  CHECK_THROWS_AS(collider_mesh(shapes()[0], 0, {.plane_half = 0}), mbi::Error);  // pipeline's
}

TEST_CASE("pick_collider: the nearest collider under the ray, never a plane", "[interact][collider]") {
  const std::vector<Collider> cs = {Collider::plane({0, 0, 0}, {0, 0, 1}), Collider::sphere({0, 0, 5}, 1),
                                    Collider::sphere({0, 0, 2}, 0.5)};
  const Ray down{{0, 0, 10}, {0, 0, -1}};
  const std::optional<ColliderHit> h = pick_collider(down, cs, 0);
  REQUIRE(h);
  CHECK(h->collider == 1);
  CHECK(h->hit.point.z() == Approx(6).margin(1e-9));  // the pole is a vertex of the mesh
  const std::optional<ColliderHit> beside = pick_collider({{0.2, 0, 10}, {0, 0, -1}}, {cs[0], cs[2]}, 0);
  REQUIRE(beside);
  CHECK(beside->collider == 1);
  CHECK(beside->hit.point.z() == Approx(2 + std::sqrt(0.25 - 0.04)).margin(0.01));  // the mesh is inscribed
  CHECK_FALSE(pick_collider(down, {cs[0]}, 0));             // a plane is never picked
  CHECK_FALSE(pick_collider({{3, 0, 10}, {0, 0, -1}}, cs, 0));  // a miss
}

TEST_CASE("dragged: the collider moves by the displacement within dt at constant velocity, then rests", "[interact][collider]") {
  for (const Collider& c : shapes()) {
    const Eigen::Vector3d d(0.3, -0.1, 0.2);
    const double t = 2.0, dt = 0.04;
    const Collider g = dragged(c, t, d, dt);
    const Collider at = mbi::pipeline::posed(c, t);
    for (const double s : {0.0, 0.5, 1.0, 3.0}) {
      const Collider p = mbi::pipeline::posed(g, t + s * dt);
      CHECK((p.point - (at.point + std::min(s, 1.0) * d)).norm() < 1e-12);
    }
    const Eigen::Vector3d q = at.point + Eigen::Vector3d(0.1, 0.1, 0.1);
    CHECK((mbi::pipeline::collider_velocity(g, q, t + 0.5 * dt) - d / dt).norm() < 1e-9);
    CHECK(mbi::pipeline::collider_velocity(g, q, t + 2 * dt).norm() == 0);
    CHECK((mbi::pipeline::collider_displacement(g, q, t, t + dt) - d).norm() < 1e-12);
    const Collider now = dragged(c, t, d, 0);  // paused: at once
    CHECK((now.point - (at.point + d)).norm() < 1e-12);
    CHECK(mbi::pipeline::signed_distance(now, q + d, 7).value == Approx(mbi::pipeline::signed_distance(at, q, 7).value));
  }
  CHECK_THROWS_AS(dragged(shapes()[0], 0, {NAN, 0, 0}, 0.1), Error);
  CHECK_THROWS_AS(dragged(shapes()[0], 0, {0, 0, 0}, -0.1), Error);
}

TEST_CASE("a mesh collider is drawn by its own triangles at its pose, on its level set's zero within a voxel",
          "[interact][collider]") {
  Eigen::MatrixXd V(8, 3);
  for (int i = 0; i < 8; ++i) V.row(i) << (i & 1) * 0.6, ((i >> 1) & 1) * 0.4, ((i >> 2) & 1) * 0.5;
  Eigen::MatrixXi F(12, 3);
  F << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5;
  std::shared_ptr<const mbi::pipeline::MeshLevelSet> level_set;
  try {
    level_set = std::make_shared<const mbi::pipeline::MeshLevelSet>(V, F);
  } catch (const mbi::Error& e) {
    mbi::test::skip(e.what());  // a build without OpenVDB
  }
  Collider c = Collider::mesh(level_set);
  c.point = {1, -2, 0.5};
  c.axes = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()).toRotationMatrix();
  c.motion.velocity = {0, 1, 0};
  const ColliderMesh m = collider_mesh(c, 2.0);
  REQUIRE(m.F.rows() == F.rows());
  const Eigen::Vector3d shift = c.point + Eigen::Vector3d(0, 2, 0);  // moved 2 m up by t = 2 s
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d expected = shift + c.axes * V.row(F(f, k)).transpose();
      CHECK((m.V.row(m.F(f, k)).transpose() - expected).norm() < 1e-12);
      CHECK(std::abs(mbi::pipeline::signed_distance(c, expected, 2.0).value) <= level_set->voxel_size());
    }
  const std::optional<ColliderHit> h = pick_collider({shift + Eigen::Vector3d(0.2, 5, 0.2), {0, -1, 0}}, {c}, 2.0);
  REQUIRE(h);
  CHECK(h->hit.point.y() == Approx(shift.y() + 0.4));  // the top face
}
