#pragma once
// The orbit camera's maths, without any window or GL (so they are tested headless).
//
// Orthographic orbit camera: it looks at `target` along the direction given by yaw and pitch
// (radians), `radius` is half the height of the visible region (world units). Mouse positions
// are in window coordinates (logical pixels, y down, as GLFW reports them); on HiDPI screens
// the framebuffer has `scale` times as many pixels, and everything here converts through the
// window size, so clicks land where the cursor is whatever the scale. Every call is O(1) and
// throws nothing: any input leaves the camera finite.
#include <mbi/interact/pick.hpp>

#include <Eigen/Core>

namespace mbi::interact {

class Camera {
 public:
  /// Frames the axis-aligned box [lo, hi] with `up` up.
  void frame(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
             const Eigen::Vector3d& up = Eigen::Vector3d::UnitY());
  void orbit(double dx_pixels, double dy_pixels);           ///< drag: rotate about the target
  /// drag: move the target, at most kMaxPan times the framed depth from where frame() put it
  void pan(double dx_pixels, double dy_pixels, int window_height);
  void zoom(double steps);                                  ///< wheel / pinch: > 0 zooms in
  // Any input leaves the camera finite (a NaN move is ignored): one move counts at most
  // kMaxMove pixels, yaw stays in [-pi, pi], pitch in [-1.5, 1.5], radius in [1e-9, 1e12].
  static constexpr double kMaxMove = 1e5, kMaxPan = 1e3;

  Eigen::Vector3d direction() const;  ///< from the eye into the scene (unit)
  Eigen::Vector3d up() const;         ///< unit, orthogonal to direction()
  Eigen::Vector3d right() const;
  /// World -> clip for a viewport of aspect width / height.
  Eigen::Matrix4d view_projection(double aspect) const;
  /// The ray through window point (x, y) of a window_w x window_h window: unit direction,
  /// origin `depth` before the target's plane.
  Ray ray(double x, double y, int window_w, int window_h) const;
  /// Window coordinates of world point p (inverse of ray(): ray(project(p)) passes through p).
  Eigen::Vector2d project(const Eigen::Vector3d& p, int window_w, int window_h) const;

  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d home = Eigen::Vector3d::Zero();  ///< the target frame() chose
  double radius = 1.0;  ///< half the visible height (world units)
  double depth = 10.0;  ///< half the depth range around the target
  double yaw = 0.6, pitch = 0.35;
  Eigen::Vector3d world_up = Eigen::Vector3d::UnitY();
};

/// Window coordinates of a framebuffer pixel on a HiDPI screen (framebuffer = scale x window).
inline Eigen::Vector2d window_from_framebuffer(const Eigen::Vector2d& fb, double scale) { return fb / scale; }

}  // namespace mbi::interact
