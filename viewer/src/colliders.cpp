#include "colliders.hpp"

#include <algorithm>
#include <cmath>

namespace mbi::viewer {
namespace {

// A plane collider as a ground square about the model's middle, the size of the looks' ground.
gpu::Ground plane_ground(const pipeline::Collider& plane, const Stage& stage, const Eigen::Vector3d& background) {
  const interact::ColliderMesh square =
      interact::collider_mesh(plane, stage.time(), {.plane_half = 1.5 * stage.size, .plane_center = 0.5 * (stage.lo + stage.hi)});
  gpu::Ground g;
  g.center = square.V.colwise().mean().transpose();
  g.e1 = (square.V.row(1) - square.V.row(0)).normalized().transpose();
  g.e2 = (square.V.row(3) - square.V.row(0)).normalized().transpose();
  g.half = 1.5 * stage.size;
  g.spacing = std::pow(10.0, std::floor(std::log10(stage.size / 4)));
  g.shadow_soft = 0.1 * stage.size;
  g.background = background;
  return g;
}

}  // namespace

CollidersNow colliders_now(const Stage& stage, gpu::Ground* looks_ground, const Eigen::Vector3d& up) {
  CollidersNow now;
  const pipeline::SurfaceContact* contact = stage.contact();
  if (!contact || stage.d != 3 || !(stage.size > 0)) return now;
  bool ground_placed = false;
  for (size_t i = 0; i < contact->colliders().size(); ++i) {
    const pipeline::Collider& c = contact->colliders()[i];
    if (c.shape != pipeline::ColliderShape::Plane) {
      now.solids.push_back(interact::collider_mesh(c, stage.time()));
      now.solid_index.push_back(static_cast<int>(i));
      continue;
    }
    const pipeline::Collider p = pipeline::posed(c, stage.time());
    if (looks_ground && !ground_placed && p.normal.dot(up.normalized()) > 0.999) {
      looks_ground->center += p.normal.dot(p.point - looks_ground->center) * p.normal;
      ground_placed = true;
      continue;
    }
    now.planes.push_back(plane_ground(c, stage, looks_ground ? kBackground : Eigen::Vector3d(1, 1, 1)));
  }
  return now;
}

void draw_colliders(gpu::Renderer& renderer, const CollidersNow& colliders, int grabbed,
                    const Eigen::Matrix4d& view_projection, const Eigen::Vector3d& eye_direction) {
  for (const gpu::Ground& g : colliders.planes) renderer.draw_ground(g, view_projection);
  for (size_t k = 0; k < colliders.solids.size(); ++k) {
    const interact::ColliderMesh& m = colliders.solids[k];
    const bool held = colliders.solid_index[k] == grabbed;
    renderer.draw_mesh(m.V, m.N, m.F, view_projection, eye_direction,
                       held ? Eigen::Vector3d(0.45, 0.62, 0.92) : Eigen::Vector3d(0.55, 0.62, 0.72));
  }
}

}  // namespace mbi::viewer
