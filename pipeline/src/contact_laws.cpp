#include <mbi/pipeline/contact_laws.hpp>

#include <algorithm>
#include <cmath>

namespace mbi::pipeline::contact {

Law normal_energy(double d, double k, double depth) {
  if (d >= 0) return {};
  if (std::isinf(depth)) return {0.5 * k * d * d, k * d, k};
  // g(z) = -z - log(1 - z), z = -d / depth, to z = kSteep; beyond, its quadratic continuation.
  constexpr double kSteep = 0.99;
  const double z = -d / depth, zc = std::min(z, kSteep), w = z - zc;
  // The series where -z - log(1 - z) would cancel.
  const double g = zc < 1e-3 ? zc * zc * (0.5 + zc * (1.0 / 3 + zc * (0.25 + zc * 0.2))) : -zc - std::log1p(-zc);
  const double g1 = zc / (1 - zc), g2 = 1 / ((1 - zc) * (1 - zc));
  return {k * depth * depth * (g + w * (g1 + 0.5 * w * g2)), -k * depth * (g1 + w * g2), k * g2};
}

double friction_f0(double y, double eps) {
  return y < eps ? -y * y * y / (3 * eps * eps) + y * y / eps + eps / 3 : y;
}

double friction_f1_over_y(double y, double eps) { return y < eps ? 2 / eps - y / (eps * eps) : 1 / y; }

Eigen::Matrix2d friction_hessian(const Eigen::Vector2d& u, double eps) {
  const double y = u.norm();
  Eigen::Matrix2d H = friction_f1_over_y(y, eps) * Eigen::Matrix2d::Identity();
  if (y == 0) return H;
  // d(f1/y)/dy / y: -1 / (eps^2 y) inside the smoothing, -1 / y^3 beyond.
  const double c = y < eps ? -1 / (eps * eps * y) : -1 / (y * y * y);
  H.noalias() += c * u * u.transpose();
  return H;
}

double advance(const Collider& collider, const Eigen::Vector3d& p, const Eigen::Vector3d& dp, double time,
               double depth) {
  if (dp.norm() == 0 || std::isinf(depth)) return 1.0;
  return advance(collider, p, dp, time, depth, signed_distance(collider, p, time).value);
}

double advance(const Collider& collider, const Eigen::Vector3d& p, const Eigen::Vector3d& dp, double time,
               double depth, double distance) {
  const double length = dp.norm();
  if (length == 0 || std::isinf(depth)) return 1.0;
  const double room0 = distance + depth;
  if (!(room0 > 0)) return 1.0;  // already past the depth (moved there by kinematic nodes): not guarded
  const double keep = 0.1 * room0;
  if (collider.shape == ColliderShape::Plane) {
    const double rate = signed_distance(collider, p + dp, time).value + depth - room0;  // linear in s
    return rate >= 0 ? 1.0 : std::min(1.0, (room0 - keep) / -rate);
  }
  // the distance falls by at most lipschitz x the distance moved (1 for an exact distance)
  const double fastest = distance_lipschitz(collider) * length;
  double s = 0.0, room = room0;
  for (int it = 0; it < 100 && room > 2 * keep; ++it) {
    const double next = s + (room - keep) / fastest;
    if (next >= 1.0) return 1.0;
    s = next;
    room = signed_distance(collider, p + s * dp, time).value + depth;
  }
  return s;
}

}  // namespace mbi::pipeline::contact
