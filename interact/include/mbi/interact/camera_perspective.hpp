#pragma once
// The page's camera: a perspective camera orbiting a model's centre about its up axis, for
// WebGL (clip z in [-1, 1]). Pixels are (x, y) of a width x height viewport, y down.
#include <mbi/interact/pick.hpp>

#include <Eigen/Core>

#include <optional>

namespace mbi::interact {

class PerspectiveCamera {
 public:
  static constexpr double kFov = 0.6;                  ///< vertical field of view, radians
  static constexpr double kDefaultYaw = 0.6, kDefaultPitch = 0.25;  ///< radians
  static constexpr double kMaxPitch = 1.5;             ///< |pitch| <= this: never along up
  static constexpr double kPerPixel = 0.01;            ///< radians turned per pixel dragged
  static constexpr double kZoomPerUnit = 0.001;        ///< zoom(dy) scales the distance by exp(dy * this)
  static constexpr double kDistance = 1.8;             ///< the first distance, times size
  static constexpr double kMinDistance = 0.05, kMaxDistance = 50;  ///< the distance's range, times size
  static constexpr double kNear = 0.01, kFar = 100;    ///< clip planes, times size
  static constexpr double kMaxMove = 1e5;              ///< one orbit or zoom counts at most this much
  static constexpr double kMinSize = 1e-100, kMaxSize = 1e100;  ///< sizes whose matrix stays finite

  /// Looks at `center` from kDistance * size away (size: the model's extent, world units), at
  /// yaw about `up` (any length) and pitch above the plane normal to it, pitch clamped to
  /// +-kMaxPitch. Throws Error on a non-finite center, yaw or pitch, a size outside
  /// [kMinSize, kMaxSize] and a zero or non-finite up.
  PerspectiveCamera(const Eigen::Vector3d& center, double size, const Eigen::Vector3d& up,
                    double yaw = kDefaultYaw, double pitch = kDefaultPitch);

  /// The camera's axes, unit and orthogonal: forward (into the picture), right and up.
  struct Frame {
    Eigen::Vector3d forward, right, up;
  };
  Eigen::Vector3d eye() const;
  Frame frame() const;

  /// A drag of (dx, dy) pixels: yaw turns by -dx * kPerPixel, pitch by dy * kPerPixel (clamped).
  /// A NaN move is ignored; one move counts at most kMaxMove pixels.
  void orbit(double dx, double dy);
  /// Wheel: > 0 moves away. The distance stays in [kMinDistance, kMaxDistance] * size.
  void zoom(double dy);

  /// Projection * view (world -> clip) for a width x height viewport.
  Eigen::Matrix4d view_projection(int width, int height) const;
  /// The pixel where world point p appears; nullopt when p is nearer than the near plane (or
  /// behind the eye). The inverse of ray(): ray(project(p)) passes through p.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p, int width, int height) const;
  /// The ray from the eye through pixel (x, y); its direction is forward plus the pixel's
  /// offsets along right and up (not unit length).
  Ray ray(double x, double y, int width, int height) const;
  // The three above throw Error on a width or height < 1 and on a non-finite point or pixel.

  const Eigen::Vector3d& center() const { return center_; }
  double size() const { return size_; }
  double yaw() const { return yaw_; }      ///< in [-pi, pi]
  double pitch() const { return pitch_; }  ///< in [-kMaxPitch, kMaxPitch]
  double distance() const { return distance_; }

 private:
  Eigen::Vector3d center_, up_;
  Eigen::Vector3d a_, b_;  // with up_, the orbit's frame: yaw 0 looks from a_, yaw pi/2 from b_
  double size_, yaw_, pitch_, distance_;
};

}  // namespace mbi::interact
