#pragma once
// Colliders under the mouse: a rigid collider of surface contact (pipeline/colliders.hpp) as
// triangles at its pose (pipeline::collider_mesh), to draw it and to pick it with cast(), and the
// motion that carries a grabbed collider to the cursor within one step, so that the contact
// solve sees its velocity.
//
//   ColliderMesh m = collider_mesh(ball, time, {.plane_half = 2, .plane_center = middle});
//   std::optional<ColliderHit> h = pick_collider(ray, colliders, time);   // planes never
//   contact.set_collider(h->collider, dragged(colliders[h->collider], time, to - from, dt));
#include <mbi/interact/pick.hpp>
#include <mbi/pipeline/collider_mesh.hpp>
#include <mbi/pipeline/colliders.hpp>

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace mbi::interact {

/// A collider as triangles at its pose (pipeline's: what mbi run's pictures draw too).
using pipeline::ColliderMesh;
using pipeline::ColliderMeshOptions;
using pipeline::collider_mesh;

struct ColliderHit {
  int collider = -1;  ///< index into the colliders given
  Hit hit;            ///< on its collider_mesh (face, t, point)
};

/// The collider whose collider_mesh at `time` the ray meets first (cast(), ties to the lower
/// index); planes are never picked (a click on the floor orbits). nullopt on a miss. Throws
/// Error as cast() on a bad ray. O(triangles of the colliders: about 1,000 per analytic shape).
std::optional<ColliderHit> pick_collider(const Ray& ray, const std::vector<pipeline::Collider>& colliders, double time);

/// `collider` as it is at `time`, carried by `displacement` (m): with dt > 0 (s) at constant
/// velocity displacement / dt from `time` to `time + dt` and at rest after (its motion), so that
/// contact sees a moving collider (friction, advancement); with dt = 0 moved at once (no step
/// follows: the simulation is paused). Its scripted motion, if any, ends at `time`. Throws Error
/// on a non-finite displacement, a dt < 0 or not finite, a non-finite time.
pipeline::Collider dragged(const pipeline::Collider& collider, double time, const Eigen::Vector3d& displacement,
                           double dt);

}  // namespace mbi::interact
