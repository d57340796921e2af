#pragma once
// The viewer's camera and picking, without any window or GL (so they are tested headless).
//
// Orthographic orbit camera: it looks at `target` along the direction given by yaw and pitch,
// `radius` is half the height of the visible region. Mouse positions are in window coordinates
// (what GLFW reports: logical pixels, y down); on HiDPI screens the framebuffer has `scale` times
// as many pixels, and everything here converts through the window size, so clicks land where
// the cursor is whatever the scale.
#include <Eigen/Core>

#include <optional>

namespace mbi::viewer {

struct Ray {
  Eigen::Vector3d origin, direction;  ///< direction unit length, from the eye into the scene
};

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
  /// The ray through window point (x, y) of a window_w x window_h window.
  Ray ray(double x, double y, int window_w, int window_h) const;
  /// Window coordinates of world point p (inverse of ray()).
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

struct Hit {
  int face = -1;
  double t = 0;                          ///< distance along the ray
  Eigen::Vector3d bary = Eigen::Vector3d::Zero();  ///< barycentric coordinates in the face
  Eigen::Vector3d point = Eigen::Vector3d::Zero(); ///< the hit point (deformed)
};

/// The first triangle of (V n x 3, F t x 3) that the ray hits (Moller-Trumbore, both sides).
std::optional<Hit> cast(const Ray& ray, const Eigen::Ref<const Eigen::MatrixXd>& V,
                        const Eigen::Ref<const Eigen::MatrixXi>& F);

/// Stiffness (N/m) of a poke spring that pulls a grabbed region of mass m (kg) with a natural
/// response time `response` (s): k = m (2 pi / response)^2. The response does not depend on the
/// model's mass or size.
double poke_stiffness(double mass, double response);

/// The poke target, bounded: the point on the plane through `grab` facing the camera under the
/// ray, moved back toward `grab` so that it is at most `max_distance` away (a flick or a drag far
/// off screen can never ask for an unbounded force).
Eigen::Vector3d poke_target(const Ray& ray, const Eigen::Vector3d& grab, const Eigen::Vector3d& view_dir,
                            double max_distance);

}  // namespace mbi::viewer
