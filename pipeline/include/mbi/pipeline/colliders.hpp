#pragma once
// Rigid colliders for contact at the dense surface (method.md fact 15): a half-space, a sphere,
// a box and a capsule (exact distances), and a closed triangle mesh (a MeshLevelSet: distances
// within a voxel), each static or moving by a scripted rigid motion, each with a Coulomb
// friction coefficient.
//
//   Collider floor = Collider::plane({0, 0, 0}, {0, 1, 0}, 0.5);
//   Collider ball = Collider::sphere({0, 1, 0}, 0.2);
//   ball.motion.velocity = {1, 0, 0};                 // sim::RigidMotion, from time 0
//   check_collider(ball, "collider 1");               // Error naming the field at fault
//   Distance d = signed_distance(ball, p, t);         // d.value < 0 inside, d.normal = grad
//
// Units: m, s (the simulator's). The shape is given at its pose at motion.start (or at any
// time for a static collider); at time t it is that shape moved by the motion's rigid map of
// t (sim::RigidMotion: p(t) = center + velocity s + Rot(axis, w s) (p0 - center)).
#include <mbi/pipeline/mesh_level_set.hpp>
#include <mbi/sim/simulator.hpp>

#include <Eigen/Core>
#include <memory>
#include <string>

namespace mbi::pipeline {

enum class ColliderShape { Plane, Sphere, Box, Capsule, Mesh };

/// One rigid collider. Build it with the named constructors; the fields each shape uses:
///   Plane:   point, normal (solid where dot(normal, x - point) < 0; normal need not be unit)
///   Sphere:  point (centre), radius
///   Box:     point (centre), half_extents (> 0), axes (columns: the box's unit axes, a rotation)
///   Capsule: point and end (the axis segment), radius
///   Mesh:    level_set, placed by point (translation) and axes (rotation): world = point + axes local
struct Collider {
  ColliderShape shape = ColliderShape::Plane;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();        ///< m
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();      ///< plane only
  Eigen::Vector3d end = Eigen::Vector3d::Zero();          ///< m, capsule only
  Eigen::Vector3d half_extents = Eigen::Vector3d::Ones(); ///< m, box only
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();     ///< box and mesh
  std::shared_ptr<const MeshLevelSet> level_set;          ///< mesh only (shared, immutable)
  double radius = 0.0;                                    ///< m, sphere and capsule
  double friction = 0.0;                                  ///< Coulomb mu, finite, >= 0
  sim::RigidMotion motion;                                ///< default: static

  static Collider plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double friction = 0.0);
  static Collider sphere(const Eigen::Vector3d& center, double radius, double friction = 0.0);
  static Collider box(const Eigen::Vector3d& center, const Eigen::Vector3d& half_extents,
                      const Eigen::Matrix3d& axes = Eigen::Matrix3d::Identity(), double friction = 0.0);
  static Collider capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                          double friction = 0.0);
  /// The level set's mesh where it was built (point 0, axes identity).
  static Collider mesh(std::shared_ptr<const MeshLevelSet> level_set, double friction = 0.0);
};

/// Throws mbi::Error "<name>: <field> ..." for a non-finite or out-of-range field (zero
/// normal, radius or half extent <= 0, axes not a rotation to 1e-9, a mesh without a level set,
/// friction NaN or < 0, motion fields as sim::Simulator::add_kinematic checks them).
void check_collider(const Collider& collider, const std::string& name);

struct Distance {
  double value = 0.0;                               ///< m, signed: < 0 inside the solid
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  ///< unit gradient of value (outward)
};

/// Signed distance from p (m) to the collider at time t (s), and its gradient. Exact for every
/// analytic shape, within a voxel for a mesh (MeshLevelSet::sample). Where the gradient is
/// undefined (a sphere's centre, a capsule's axis, a box's medial surface) the normal is one of
/// the one-sided gradients.
Distance signed_distance(const Collider& collider, const Eigen::Vector3d& p, double time);
/// The collider as it is at `time`, static (its motion reset): the same distances at any time as
/// `collider` has at `time` (to round-off), cheaper to evaluate many times; a plane's normal unit.
Collider posed(const Collider& collider, double time);

/// A bound on |gradient| of signed_distance's value: 1 for the analytic shapes (distances), the
/// level set's lipschitz() for a mesh. A point that moves by r changes its distance by at most
/// this times r (conservative advancement, broad phases).
double distance_lipschitz(const Collider& collider);

/// Velocity (m/s) at time t of the collider's material point that is at p then.
Eigen::Vector3d collider_velocity(const Collider& collider, const Eigen::Vector3d& p, double time);

/// Displacement (m) from time `from` to time `to` (s) of the collider's material point that is
/// at p at time `from`: its rigid motion's map of `to` after the inverse map of `from`.
Eigen::Vector3d collider_displacement(const Collider& collider, const Eigen::Vector3d& p, double from,
                                      double to);

}  // namespace mbi::pipeline
