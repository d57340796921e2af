// Colliders as triangles, picked and dragged (collider.hpp).
#include <mbi/interact/collider.hpp>
#include <mbi/interact/error.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <string>

namespace mbi::interact {

using pipeline::Collider;
using pipeline::ColliderShape;

std::optional<ColliderHit> pick_collider(const Ray& ray, const std::vector<Collider>& colliders, double time) {
  std::optional<ColliderHit> best;
  for (size_t i = 0; i < colliders.size(); ++i) {
    if (colliders[i].shape == ColliderShape::Plane) continue;
    const ColliderMesh m = collider_mesh(colliders[i], time);
    const std::optional<Hit> h = cast(ray, m.V, m.F);
    if (h && (!best || h->t < best->hit.t)) best = ColliderHit{static_cast<int>(i), *h};
  }
  return best;
}

Collider dragged(const Collider& collider, double time, const Eigen::Vector3d& displacement, double dt) {
  if (!displacement.allFinite()) throw Error("dragged: the displacement is not finite");
  if (!std::isfinite(dt) || dt < 0) throw Error("dragged: dt must be finite and >= 0 s, got " + std::to_string(dt));
  if (!std::isfinite(time)) throw Error("dragged: the time is not finite");
  Collider c = pipeline::posed(collider, time);
  if (dt == 0) {
    c.point += displacement;
    c.end += displacement;
    return c;
  }
  c.motion.velocity = displacement / dt;
  c.motion.start = time;
  c.motion.stop = time + dt;
  return c;
}

}  // namespace mbi::interact
