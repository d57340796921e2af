#pragma once
// The looks of the 3D views (internal): a ground plane under the model with a light grid and a
// soft contact shadow, and the surface in a clay-like material (a matcap: the colour depends on
// the normal as the camera sees it, so the shape reads from any side), both drawn by
// gpu::Renderer; here where the ground lies and its shadow falls. The software looks keep the
// same picture, only cheaper in the window (no MSAA).
#include <mbi/gpu/renderer.hpp>
#include <mbi/viewer/camera.hpp>

#include <Eigen/Core>

namespace mbi::viewer {

/// The background of the looks (RGB, 0..1): light, so that the ground's edge fades into it.
inline const Eigen::Vector3d kBackground(0.96, 0.965, 0.975);

/// The ground under a model and the shadow on it, in the ground's plane coordinates (e1, e2).
struct Ground : gpu::Ground {
  Eigen::Vector2d mid = Eigen::Vector2d::Zero();     ///< the model's middle at rest, in (e1, e2)
  Eigen::Vector2d margin = Eigen::Vector2d::Zero();  ///< of the control mesh around the model at rest
};

/// The ground under the model at rest P (dense points, p x 3) along `up`, U (n x 3) the control
/// mesh at rest; no shadow yet. Once per model.
Ground ground_at_rest(const Eigen::MatrixXd& U, const Eigen::MatrixXd& P, const Eigen::Vector3d& up);
/// The shadow cast straight down by the control mesh now (X, n x 3), less the margin it has
/// around the model at rest. Every frame.
void cast_shadow(Ground& ground, const Eigen::MatrixXd& X);

/// World -> camera of `camera` for gpu::Renderer::draw_material (rows: right, up, toward the eye).
Eigen::Matrix3d view_rotation(const Camera& camera);

}  // namespace mbi::viewer
