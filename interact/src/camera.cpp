// The orbit camera (camera.hpp).
#include <mbi/interact/camera.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace mbi::interact {

void Camera::frame(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& up_dir) {
  target = home = 0.5 * (lo + hi);
  const double r = 0.5 * (hi - lo).norm();
  radius = 1.15 * std::max(r, 1e-9);
  depth = 4 * std::max(r, 1e-9);
  world_up = up_dir.normalized();
}

// Mouse moves of any size, even past the largest double, leave the camera finite: a move is
// clamped to kMaxMove pixels, yaw wraps, pitch, radius and the distance panned are bounded.
void Camera::orbit(double dx, double dy) {
  if (std::isnan(dx) || std::isnan(dy)) return;
  const double pi = std::acos(-1.0);
  yaw = std::remainder(yaw + 0.01 * std::clamp(dx, -kMaxMove, kMaxMove), 2 * pi);
  pitch = std::clamp(pitch + 0.01 * std::clamp(dy, -kMaxMove, kMaxMove), -1.5, 1.5);
}

void Camera::pan(double dx, double dy, int window_height) {
  if (std::isnan(dx) || std::isnan(dy)) return;
  const double per_pixel = 2 * radius / std::max(window_height, 1);
  const Eigen::Vector3d moved = target - std::clamp(dx, -kMaxMove, kMaxMove) * per_pixel * right() +
                                std::clamp(dy, -kMaxMove, kMaxMove) * per_pixel * up();
  const Eigen::Vector3d away = moved - home;
  const double reach = kMaxPan * std::max(depth, 1e-9);
  target = away.norm() > reach ? Eigen::Vector3d(home + away * (reach / away.norm())) : moved;
}

void Camera::zoom(double steps) {
  if (std::isnan(steps)) return;
  radius = std::clamp(radius * std::pow(0.9, std::clamp(steps, -1e4, 1e4)), 1e-9, 1e12);
}

Eigen::Vector3d Camera::direction() const {
  // world_up and a horizontal reference build the orbit frame
  Eigen::Vector3d ref = world_up.cross(Eigen::Vector3d::UnitX());
  if (ref.norm() < 0.5) ref = world_up.cross(Eigen::Vector3d::UnitZ());
  ref.normalize();
  const Eigen::Vector3d side = world_up.cross(ref);
  const Eigen::Vector3d horizontal = std::cos(yaw) * ref + std::sin(yaw) * side;
  // from the eye (above and in front) into the scene
  return -(std::cos(pitch) * horizontal + std::sin(pitch) * world_up).normalized();
}

Eigen::Vector3d Camera::right() const { return direction().cross(world_up).normalized(); }
Eigen::Vector3d Camera::up() const { return right().cross(direction()).normalized(); }

Eigen::Matrix4d Camera::view_projection(double aspect) const {
  const Eigen::Vector3d f = direction(), r = right(), u = up();
  const double hw = radius * aspect, hh = radius;
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  M.block<1, 3>(0, 0) = r.transpose() / hw;
  M(0, 3) = -r.dot(target) / hw;
  M.block<1, 3>(1, 0) = u.transpose() / hh;
  M(1, 3) = -u.dot(target) / hh;
  M.block<1, 3>(2, 0) = f.transpose() / depth;
  M(2, 3) = -f.dot(target) / depth;
  M(3, 3) = 1;
  return M;
}

Ray Camera::ray(double x, double y, int w, int h) const {
  const double aspect = static_cast<double>(w) / std::max(h, 1);
  const double nx = 2 * x / std::max(w, 1) - 1, ny = 1 - 2 * y / std::max(h, 1);
  Ray r;
  r.direction = direction();
  r.origin = target + nx * radius * aspect * right() + ny * radius * up() - depth * r.direction;
  return r;
}

Eigen::Vector2d Camera::project(const Eigen::Vector3d& p, int w, int h) const {
  const double aspect = static_cast<double>(w) / std::max(h, 1);
  const double nx = (p - target).dot(right()) / (radius * aspect);
  const double ny = (p - target).dot(up()) / radius;
  return {(nx + 1) * 0.5 * w, (1 - ny) * 0.5 * h};
}

}  // namespace mbi::interact
