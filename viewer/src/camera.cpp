#include <mbi/viewer/camera.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace mbi::viewer {

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

std::optional<Hit> cast(const Ray& ray, const Eigen::Ref<const Eigen::MatrixXd>& V,
                        const Eigen::Ref<const Eigen::MatrixXi>& F) {
  // a ray through a shared vertex or edge (a click at the middle of a regular grid) must not
  // miss every triangle by rounding: a little slack, the barycentrics then clamped
  constexpr double slack = 1e-9;
  std::optional<Hit> best;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::Vector3d e1 = b - a, e2 = c - a;
    const Eigen::Vector3d p = ray.direction.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-300) continue;
    const double inv = 1 / det;
    const Eigen::Vector3d s = ray.origin - a;
    double u = s.dot(p) * inv;
    if (u < -slack || u > 1 + slack) continue;
    const Eigen::Vector3d q = s.cross(e1);
    double v = ray.direction.dot(q) * inv;
    if (v < -slack || u + v > 1 + slack) continue;
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0 - u);
    const double t = e2.dot(q) * inv;
    if (t < 0 || !std::isfinite(t)) continue;
    if (!best || t < best->t) {
      Hit h;
      h.face = static_cast<int>(f);
      h.t = t;
      h.bary = Eigen::Vector3d(1 - u - v, u, v);
      h.point = ray.origin + t * ray.direction;
      best = h;
    }
  }
  return best;
}

double poke_stiffness(double mass, double response) {
  const double w = 2 * std::acos(-1.0) / std::max(response, 1e-6);
  return std::max(mass, 0.0) * w * w;
}

Eigen::Vector3d poke_target(const Ray& ray, const Eigen::Vector3d& grab, const Eigen::Vector3d& view_dir,
                            double max_distance) {
  const Eigen::Vector3d n = view_dir.normalized();
  const double denom = ray.direction.dot(n);
  Eigen::Vector3d p = grab;
  if (std::abs(denom) > 1e-12) {
    const double t = (grab - ray.origin).dot(n) / denom;
    if (std::isfinite(t)) p = ray.origin + t * ray.direction;
  }
  if (!p.allFinite()) return grab;
  const Eigen::Vector3d d = p - grab;
  const double len = d.norm();
  if (len > max_distance && len > 0) p = grab + d * (max_distance / len);
  return p;
}

}  // namespace mbi::viewer
