#pragma once
// The looks of the 3D views (internal): a ground plane under the model with a light grid and a
// soft contact shadow, and the surface in a clay-like material computed in the shader (a matcap:
// the colour depends on the normal as the camera sees it, so the shape reads from any side).
// The software looks keep the same picture, only cheaper in the window (no MSAA).
#include <mbi/gpu/evaluator.hpp>
#include <mbi/gpu/surface.hpp>
#include <mbi/viewer/camera.hpp>

#include <Eigen/Core>

namespace mbi::viewer {

/// The background of the looks (RGB, 0..1): light, so that the ground's edge fades into it.
inline constexpr double kBackground[3] = {0.96, 0.965, 0.975};

/// The ground under a model and the shadow on it, in the ground's plane coordinates (e1, e2).
struct Ground {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< on the plane, under the model's middle
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX(), e2 = Eigen::Vector3d::UnitZ();  ///< unit, in the plane
  double half = 1;     ///< half the side of the square drawn (world units)
  double spacing = 1;  ///< between grid lines (a power of ten, world units)
  Eigen::Vector2d shadow_center = Eigen::Vector2d::Zero(), shadow_half = Eigen::Vector2d::Zero();
  double shadow_soft = 0.1;  ///< how far the shadow's edge fades (world units)
  Eigen::Vector2d mid = Eigen::Vector2d::Zero();     ///< the model's middle at rest, in (e1, e2)
  Eigen::Vector2d margin = Eigen::Vector2d::Zero();  ///< of the control mesh around the model at rest
};

/// The ground under the model at rest P (dense points, p x 3) along `up`, U (n x 3) the control
/// mesh at rest; no shadow yet. Once per model.
Ground ground_at_rest(const Eigen::MatrixXd& U, const Eigen::MatrixXd& P, const Eigen::Vector3d& up);
/// The shadow cast straight down by the control mesh now (X, n x 3), less the margin it has
/// around the model at rest. Every frame.
void cast_shadow(Ground& ground, const Eigen::MatrixXd& X);

class Scenery {
 public:
  /// Needs the viewer's GL context current. Throws Error.
  Scenery();
  ~Scenery();
  Scenery(const Scenery&) = delete;
  Scenery& operator=(const Scenery&) = delete;

  /// The dense surface's triangles (t x 3), once per model.
  void set_faces(const Eigen::MatrixXi& F);
  /// The ground into the bound framebuffer and viewport (depth written, edges fading out).
  void draw_ground(const Ground& ground, const Eigen::Matrix4d& view_projection);
  /// The evaluator's surface (3D, with normals) in the material, slightly in front of the
  /// gpu::Renderer's surface (its wireframe pass then only adds edges).
  void draw_surface(const gpu::GpuEvaluator& ev, const Eigen::Matrix4d& view_projection, const Camera& camera,
                    const Eigen::Vector3d& color);

 private:
  gpu::Surface mesh_;
  unsigned surface_ = 0, ground_ = 0, ground_vao_ = 0, corners_ = 0;
};

}  // namespace mbi::viewer
