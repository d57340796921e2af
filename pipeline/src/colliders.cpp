#include <mbi/error.hpp>
#include <mbi/pipeline/colliders.hpp>
#include <mbi/sim/rigid_pose.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace mbi::pipeline {
namespace {

[[noreturn]] void bad(const std::string& name, const std::string& what) { throw Error(name + ": " + what); }

void check_positive(const std::string& name, const char* field, double value) {
  if (!std::isfinite(value) || value <= 0)
    bad(name, std::string(field) + " must be finite and > 0 m, got " + std::to_string(value));
}

/// Unit vector along v, or any unit vector orthogonal to `fallback_axis` when v is 0.
Eigen::Vector3d direction(const Eigen::Vector3d& v, const Eigen::Vector3d& fallback_axis) {
  const double len = v.norm();
  if (len > 0) return v / len;
  return fallback_axis.unitOrthogonal();
}

Distance box_distance(const Collider& c, const Eigen::Vector3d& p) {
  const Eigen::Vector3d local = c.axes.transpose() * (p - c.point);
  const Eigen::Vector3d q = local.cwiseAbs() - c.half_extents;
  Eigen::Vector3d sign;
  for (int k = 0; k < 3; ++k) sign(k) = local(k) < 0 ? -1.0 : 1.0;
  Distance d;
  const Eigen::Vector3d out = q.cwiseMax(0.0);
  if (out.squaredNorm() > 0) {
    d.value = out.norm();
    d.normal = c.axes * (out.cwiseProduct(sign) / d.value);
  } else {  // inside or on the surface: the nearest face
    int k = 0;
    d.value = q.maxCoeff(&k);
    d.normal = sign(k) * c.axes.col(k);
  }
  return d;
}

Distance local_distance(const Collider& c, const Eigen::Vector3d& p) {
  Distance d;
  switch (c.shape) {
    case ColliderShape::Plane: {
      const double len = c.normal.norm();
      d.normal = c.normal / len;
      d.value = d.normal.dot(p - c.point);
      return d;
    }
    case ColliderShape::Sphere:
      d.normal = direction(p - c.point, Eigen::Vector3d::UnitX());
      d.value = (p - c.point).norm() - c.radius;
      return d;
    case ColliderShape::Box:
      return box_distance(c, p);
    case ColliderShape::Mesh: {
      const LevelSetSample s = c.level_set->sample(c.axes.transpose() * (p - c.point));
      d.value = s.value;
      d.normal = c.axes * s.normal;
      return d;
    }
    case ColliderShape::Capsule: {
      const Eigen::Vector3d axis = c.end - c.point;
      const double len2 = axis.squaredNorm();
      const double s = len2 > 0 ? std::clamp((p - c.point).dot(axis) / len2, 0.0, 1.0) : 0.0;
      const Eigen::Vector3d r = p - (c.point + s * axis);
      d.normal = direction(r, len2 > 0 ? axis : Eigen::Vector3d::UnitX());
      d.value = r.norm() - c.radius;
      return d;
    }
  }
  return d;
}

}  // namespace

Collider Collider::plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double friction) {
  Collider c;
  c.shape = ColliderShape::Plane;
  c.point = point;
  c.normal = normal;
  c.friction = friction;
  return c;
}

Collider Collider::sphere(const Eigen::Vector3d& center, double radius, double friction) {
  Collider c;
  c.shape = ColliderShape::Sphere;
  c.point = center;
  c.radius = radius;
  c.friction = friction;
  return c;
}

Collider Collider::box(const Eigen::Vector3d& center, const Eigen::Vector3d& half_extents,
                       const Eigen::Matrix3d& axes, double friction) {
  Collider c;
  c.shape = ColliderShape::Box;
  c.point = center;
  c.half_extents = half_extents;
  c.axes = axes;
  c.friction = friction;
  return c;
}

Collider Collider::capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, double friction) {
  Collider c;
  c.shape = ColliderShape::Capsule;
  c.point = a;
  c.end = b;
  c.radius = radius;
  c.friction = friction;
  return c;
}

Collider Collider::mesh(std::shared_ptr<const MeshLevelSet> level_set, double friction) {
  Collider c;
  c.shape = ColliderShape::Mesh;
  c.level_set = std::move(level_set);
  c.friction = friction;
  return c;
}

double distance_lipschitz(const Collider& c) {
  return c.shape == ColliderShape::Mesh && c.level_set ? c.level_set->lipschitz() : 1.0;
}

void check_collider(const Collider& c, const std::string& name) {
  if (!(std::isfinite(c.friction) && c.friction >= 0))
    bad(name, "friction must be finite and >= 0, got " + std::to_string(c.friction));
  if (!c.point.allFinite()) bad(name, "point must be finite");
  switch (c.shape) {
    case ColliderShape::Plane:
      if (!c.normal.allFinite() || c.normal.norm() == 0) bad(name, "normal must be finite and non-zero");
      break;
    case ColliderShape::Sphere: check_positive(name, "radius", c.radius); break;
    case ColliderShape::Capsule:
      if (!c.end.allFinite()) bad(name, "end must be finite");
      check_positive(name, "radius", c.radius);
      break;
    case ColliderShape::Mesh:
      if (!c.level_set) bad(name, "a mesh collider needs its level set");
      [[fallthrough]];
    case ColliderShape::Box:
      if (c.shape == ColliderShape::Box)
        for (int k = 0; k < 3; ++k) check_positive(name, "half_extents", c.half_extents(k));
      if (!c.axes.allFinite() ||
          !(c.axes.transpose() * c.axes - Eigen::Matrix3d::Identity()).isZero(1e-9) ||
          !(c.axes.determinant() > 0))
        bad(name, "axes must be a rotation (orthonormal columns, determinant +1)");
      break;
  }
  const sim::RigidMotion& m = c.motion;
  if (!m.center.allFinite() || !m.axis.allFinite() || !std::isfinite(m.angular_velocity) ||
      !m.velocity.allFinite() || std::isnan(m.start) || std::isnan(m.stop))
    bad(name, "motion has a non-finite field");
  if (m.angular_velocity != 0.0 && m.axis.norm() == 0.0) bad(name, "motion axis is zero");
  if (m.stop < m.start) bad(name, "motion stop is before start");
}

Distance signed_distance(const Collider& c, const Eigen::Vector3d& p, double time) {
  if (c.motion.velocity.isZero() && c.motion.angular_velocity == 0.0) return local_distance(c, p);  // static
  const sim::RigidPose ps = sim::rigid_pose(c.motion, time);
  const Eigen::Vector3d local = c.motion.center + ps.rot.transpose() * (p - ps.shift);
  Distance d = local_distance(c, local);
  d.normal = ps.rot * d.normal;
  return d;
}

Collider posed(const Collider& c, double time) {
  const sim::RigidPose ps = sim::rigid_pose(c.motion, time);
  const auto place = [&](const Eigen::Vector3d& local) { return ps.apply(local, c.motion.center); };
  Collider out = c;
  out.motion = sim::RigidMotion();
  out.point = place(c.point);
  out.end = place(c.end);
  out.normal = ps.rot * c.normal.normalized();
  out.axes = ps.rot * c.axes;
  return out;
}

Eigen::Vector3d collider_velocity(const Collider& c, const Eigen::Vector3d& p, double time) {
  const sim::RigidMotion& m = c.motion;
  if (!(time >= m.start && time < m.stop)) return Eigen::Vector3d::Zero();
  const sim::RigidPose ps = sim::rigid_pose(m, time);
  Eigen::Vector3d v = m.velocity;
  if (m.angular_velocity != 0.0) v += m.angular_velocity * m.axis.normalized().cross(p - ps.shift);
  return v;
}

Eigen::Vector3d collider_displacement(const Collider& c, const Eigen::Vector3d& p, double from, double to) {
  const sim::RigidPose a = sim::rigid_pose(c.motion, from), b = sim::rigid_pose(c.motion, to);
  const Eigen::Vector3d local = a.rot.transpose() * (p - a.shift);  // relative to the centre
  return b.shift + b.rot * local - p;
}

}  // namespace mbi::pipeline
