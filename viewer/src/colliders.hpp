#pragma once
// The colliders of surface contact in the views (internal): each at its pose at the simulation's
// time, a plane as a ground (a grid square, as the looks' ground) and the other shapes as shaded
// meshes (interact::collider_mesh, the triangles that picking casts against).
#include "scenery.hpp"
#include "stage.hpp"

#include <mbi/gpu/renderer.hpp>
#include <mbi/interact/collider.hpp>

#include <vector>

namespace mbi::viewer {

struct CollidersNow {
  std::vector<interact::ColliderMesh> solids;
  std::vector<int> solid_index;  ///< each solid's index among the contact's colliders
  std::vector<gpu::Ground> planes;
};

/// The stage's colliders now (none without surface contact). `looks_ground`: the looks' ground
/// (nullptr in the plain looks); a plane collider facing `up` moves it onto the plane (the model
/// rests on that plane, not on its lowest point at rest) and is not drawn again.
CollidersNow colliders_now(const Stage& stage, gpu::Ground* looks_ground, const Eigen::Vector3d& up);

/// Draws them into the bound viewport, depth tested; the grabbed one (an index among the
/// contact's colliders, -1: none) lighter.
void draw_colliders(gpu::Renderer& renderer, const CollidersNow& colliders, int grabbed,
                    const Eigen::Matrix4d& view_projection, const Eigen::Vector3d& eye_direction);

}  // namespace mbi::viewer
