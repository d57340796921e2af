#pragma once
// A rigid collider of surface contact (colliders.hpp) as triangles at its pose: what draws it
// (mbi run's pictures, the viewer, the page) and what picking casts against (interact).
//
//   ColliderMesh m = collider_mesh(ball, time, {.plane_half = 2, .plane_center = middle});
#include <mbi/pipeline/colliders.hpp>

#include <Eigen/Core>

namespace mbi::pipeline {

/// A collider's surface: triangles with a unit normal per vertex, outward (a mesh collider's: on
/// its triangles' winding side), flat faces with their own vertices; world units (m).
struct ColliderMesh {
  Eigen::MatrixXd V;  ///< n x 3
  Eigen::MatrixXd N;  ///< n x 3
  Eigen::MatrixXi F;  ///< t x 3, counter-clockwise seen from outside
};

/// A plane is infinite: it is drawn as a square of half side `plane_half` (m) about the point of
/// the plane nearest `plane_center`.
struct ColliderMeshOptions {
  double plane_half = 1.0;
  Eigen::Vector3d plane_center = Eigen::Vector3d::Zero();
};

/// The surface of `collider` at `time` (s): a sphere or a capsule as a 32 x 16 latitude-longitude
/// mesh (vertices on the exact surface), a box's six faces, a mesh collider's triangles (those
/// its level set was built from) at its pose, a plane as the square of `options`. Throws Error
/// on a plane_half <= 0 or not finite, or a non-finite plane_center.
ColliderMesh collider_mesh(const Collider& collider, double time, const ColliderMeshOptions& options = {});

}  // namespace mbi::pipeline
