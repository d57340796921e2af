#pragma once
// The rigid map of a RigidMotion at a time: the one place that turns a scripted motion into a
// pose (kinematic nodes, colliders, mesh level sets).
#include <mbi/sim/simulator.hpp>

#include <Eigen/Dense>

namespace mbi::sim {

/// world = shift + rot (local - motion.center), local being the position at motion.start.
struct RigidPose {
  Eigen::Matrix3d rot = Eigen::Matrix3d::Identity();
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();  ///< m, where the centre is at the time
  Eigen::Vector3d apply(const Eigen::Vector3d& local, const Eigen::Vector3d& center) const {
    return shift + rot * (local - center);
  }
};

/// The pose at time t (s), clamped to [start, stop]; the identity rotation when the motion does
/// not turn. O(1), no allocation, thread-safe.
RigidPose rigid_pose(const RigidMotion& m, double t);

}  // namespace mbi::sim
