// The page's perspective orbit camera (camera_perspective.hpp).
#include <mbi/interact/camera_perspective.hpp>
#include <mbi/interact/error.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace mbi::interact {
namespace {

const double kPi = std::acos(-1.0);

Eigen::Vector3d unit(const Eigen::Vector3d& v) { return v * (1 / std::hypot(v.x(), v.y(), v.z())); }

void require(bool ok, const std::string& what) {
  if (!ok) throw Error("PerspectiveCamera: " + what);
}

void require_viewport(int width, int height) {
  require(width >= 1 && height >= 1,
          "viewport " + std::to_string(width) + " x " + std::to_string(height) + " (width and height must be >= 1)");
}

}  // namespace

PerspectiveCamera::PerspectiveCamera(const Eigen::Vector3d& center, double size, const Eigen::Vector3d& up,
                                     double yaw, double pitch)
    : center_(center), size_(size) {
  require(center.allFinite(), "center must be finite");
  std::ostringstream given;
  given << size;
  require(size >= kMinSize && size <= kMaxSize, "size " + given.str() + " (must be in [1e-100, 1e100])");
  require(up.allFinite() && up.norm() > 0, "up must be a finite non-zero vector");
  require(std::isfinite(yaw) && std::isfinite(pitch), "yaw and pitch must be finite");
  up_ = unit(up);
  // a horizontal axis: up crossed with the world axis least along it
  const Eigen::Vector3d side = std::abs(up_.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  a_ = unit(up_.cross(side));
  b_ = up_.cross(a_);
  yaw_ = std::remainder(yaw, 2 * kPi);
  pitch_ = std::clamp(pitch, -kMaxPitch, kMaxPitch);
  distance_ = kDistance * size;
}

Eigen::Vector3d PerspectiveCamera::eye() const {
  const double c = std::cos(pitch_);
  const Eigen::Vector3d dir = a_ * (c * std::cos(yaw_)) + b_ * (c * std::sin(yaw_)) + up_ * std::sin(pitch_);
  return center_ + dir * distance_;
}

PerspectiveCamera::Frame PerspectiveCamera::frame() const {
  const Eigen::Vector3d f = unit(center_ - eye());
  const Eigen::Vector3d r = unit(f.cross(up_));
  return {f, r, r.cross(f)};
}

void PerspectiveCamera::orbit(double dx, double dy) {
  if (std::isnan(dx) || std::isnan(dy)) return;
  yaw_ = std::remainder(yaw_ - std::clamp(dx, -kMaxMove, kMaxMove) * kPerPixel, 2 * kPi);
  pitch_ = std::clamp(pitch_ + std::clamp(dy, -kMaxMove, kMaxMove) * kPerPixel, -kMaxPitch, kMaxPitch);
}

void PerspectiveCamera::zoom(double dy) {
  if (std::isnan(dy)) return;
  distance_ = std::clamp(distance_ * std::exp(std::clamp(dy, -kMaxMove, kMaxMove) * kZoomPerUnit),
                         kMinDistance * size_, kMaxDistance * size_);
}

Eigen::Matrix4d PerspectiveCamera::view_projection(int width, int height) const {
  require_viewport(width, height);
  const auto [f, r, u] = frame();
  const Eigen::Vector3d e = eye();
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.row(0) << r.transpose(), -r.dot(e);
  view.row(1) << u.transpose(), -u.dot(e);
  view.row(2) << -f.transpose(), f.dot(e);
  const double near = kNear * size_, far = kFar * size_;
  const double t = 1 / std::tan(kFov / 2), aspect = static_cast<double>(width) / height;
  Eigen::Matrix4d projection = Eigen::Matrix4d::Zero();
  projection(0, 0) = t / aspect;
  projection(1, 1) = t;
  projection(2, 2) = (far + near) / (near - far);
  projection(2, 3) = 2 * far * near / (near - far);
  projection(3, 2) = -1;
  return projection * view;
}

std::optional<Eigen::Vector2d> PerspectiveCamera::project(const Eigen::Vector3d& p, int width, int height) const {
  require_viewport(width, height);
  require(p.allFinite(), "project: the point must be finite");
  const auto [f, r, u] = frame();
  const Eigen::Vector3d d = p - eye();
  const double depth = d.dot(f);
  if (!(depth >= kNear * size_)) return std::nullopt;
  // ray()'s pixel offsets, inverted
  const double t = std::tan(kFov / 2), aspect = static_cast<double>(width) / height;
  const double px = d.dot(r) / depth, py = d.dot(u) / depth;
  const Eigen::Vector2d pixel((px / (t * aspect) + 1) * width / 2, (1 - py / t) * height / 2);
  require(pixel.allFinite(), "project: the point is too far from the eye");
  return pixel;
}

Ray PerspectiveCamera::ray(double x, double y, int width, int height) const {
  require_viewport(width, height);
  require(std::isfinite(x) && std::isfinite(y), "ray: the pixel must be finite");
  const auto [f, r, u] = frame();
  const double t = std::tan(kFov / 2);
  const double px = (2 * x / width - 1) * t * width / height, py = (1 - 2 * y / height) * t;
  Ray ray;
  ray.origin = eye();
  ray.direction = f + (r * px + u * py);
  require(ray.direction.allFinite(), "ray: the pixel is too far outside the viewport");
  return ray;
}

}  // namespace mbi::interact
