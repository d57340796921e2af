#pragma once
// Picking: the first triangle of a mesh under a ray.
#include <Eigen/Core>

#include <optional>

namespace mbi::interact {

/// A half-line in model coordinates: the points origin + t direction, t >= 0. The direction
/// need not be unit length; t is then in units of its length.
struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};

struct Hit {
  int face = -1;                                   ///< row of F
  double t = 0;                                    ///< the ray's parameter at the hit (>= 0)
  Eigen::Vector3d bary = Eigen::Vector3d::Zero();  ///< barycentric coordinates in the face (>= 0, sum 1)
  Eigen::Vector3d point = Eigen::Vector3d::Zero(); ///< origin + t direction
};

/// Slack of cast() in barycentric coordinates: a ray through a shared edge or vertex (a click at
/// the middle of a regular grid) hits a triangle instead of missing all of them by rounding.
inline constexpr double kPickSlack = 1e-9;

/// The first triangle of (V n x 3, F t x 3, vertex rows) that the ray hits, either side facing
/// (Moller-Trumbore; barycentrics up to `slack` outside a triangle count, then clamped into
/// it); nullopt on a miss. Ties go to the lower face. O(t).
/// Throws Error on a ray with a zero or non-finite direction or a non-finite origin, on V or
/// F without 3 columns, on F without rows, on an index of F outside V, on a slack < 0 or NaN.
std::optional<Hit> cast(const Ray& ray, const Eigen::Ref<const Eigen::MatrixXd>& V,
                        const Eigen::Ref<const Eigen::MatrixXi>& F, double slack = kPickSlack);

}  // namespace mbi::interact
