#pragma once
// The per-point laws of surface contact (method.md facts 16 and 17): the normal energy as a
// function of the signed distance, IPC's smoothed friction, and the conservative advancement
// that caps a move. SurfaceContact sums them over points; tests check them alone.
#include <mbi/pipeline/colliders.hpp>

#include <Eigen/Core>

namespace mbi::pipeline::contact {

/// A scalar law and its first two derivatives.
struct Law {
  double value = 0.0;
  double slope = 0.0;      ///< d value / d argument
  double curvature = 0.0;  ///< d^2 value / d argument^2, >= 0
};

/// Normal energy (J) of one point at signed distance d (m), stiffness k (N/m), guarded depth
/// `depth` (m, > 0): 0 for d >= 0; k depth^2 g(z), g(z) = -z - log(1 - z), z = -d / depth,
/// for 0 < z <= 0.99 (k d^2 / 2 to second order, convex, force k d depth / (depth + d));
/// beyond, g's quadratic continuation from z = 0.99 (curvature 1e4 k), so it stays finite and
/// C2. depth = infinity gives the plain penalty k d^2 / 2.
Law normal_energy(double d, double k, double depth);

/// IPC's C1 smoothing of |u| (Li et al. 2020): f0(y) = -y^3 / (3 eps^2) + y^2 / eps + eps / 3
/// for y < eps, y beyond; eps > 0 (m).
double friction_f0(double y, double eps);
/// f0'(y) / y (finite at y = 0: 2 / eps).
double friction_f1_over_y(double y, double eps);
/// Hessian of f0(|u|) for a tangential displacement u (2, m): symmetric, positive
/// semi-definite (exact for |u| < eps; beyond, |u| 's Hessian, also PSD).
Eigen::Matrix2d friction_hessian(const Eigen::Vector2d& u, double eps);

/// Conservative advancement: the largest s in [0, 1] found such that every point of the segment
/// p + s' dp, 0 <= s' <= s, keeps at least a tenth of the room d(p) + depth it had above depth
/// -depth (signed distance to `collider` at `time`); 1 when d(p) <= -depth. The distance falls
/// by at most distance_lipschitz(collider) per unit moved, so each advance by
/// (room - room_0 / 10) / (lipschitz |dp|) is safe; exact for a plane.
double advance(const Collider& collider, const Eigen::Vector3d& p, const Eigen::Vector3d& dp, double time,
               double depth);
/// The same with `distance` = the signed distance at p (at `time`), already known.
double advance(const Collider& collider, const Eigen::Vector3d& p, const Eigen::Vector3d& dp, double time,
               double depth, double distance);

}  // namespace mbi::pipeline::contact
