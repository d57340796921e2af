#include <mbi/sim/rigid_pose.hpp>

#include <algorithm>

namespace mbi::sim {

RigidPose rigid_pose(const RigidMotion& m, double t) {
  const double s = std::clamp(t, m.start, m.stop) - m.start;
  RigidPose p;
  if (m.angular_velocity != 0.0) p.rot = Eigen::AngleAxisd(m.angular_velocity * s, m.axis.normalized()).toRotationMatrix();
  p.shift = m.center + m.velocity * s;
  return p;
}

}  // namespace mbi::sim
