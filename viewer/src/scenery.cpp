#include "scenery.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

namespace mbi::viewer {
namespace {

// The extent of the points Y (rows) along e1 and e2.
void footprint(const Eigen::MatrixXd& Y, const Ground& g, Eigen::Vector2d& lo, Eigen::Vector2d& hi) {
  const Eigen::VectorXd a = Y * g.e1, b = Y * g.e2;
  lo = {a.minCoeff(), b.minCoeff()};
  hi = {a.maxCoeff(), b.maxCoeff()};
}

}  // namespace

Ground ground_at_rest(const Eigen::MatrixXd& U, const Eigen::MatrixXd& P, const Eigen::Vector3d& up_in) {
  Ground g;
  const Eigen::Vector3d up = up_in.normalized();
  const Eigen::Vector3d side = std::abs(up.x()) < 0.9 ? Eigen::Vector3d(Eigen::Vector3d::UnitX()) : Eigen::Vector3d(Eigen::Vector3d::UnitY());
  g.e1 = side.cross(up).normalized();
  g.e2 = up.cross(g.e1);
  Eigen::Vector2d cage_lo, cage_hi, model_lo, model_hi;
  footprint(U, g, cage_lo, cage_hi);
  footprint(P, g, model_lo, model_hi);
  const double size = std::max((P.colwise().maxCoeff() - P.colwise().minCoeff()).norm(), 1e-9);
  g.mid = 0.5 * (model_lo + model_hi);
  // the model stands on the ground (its lowest point, a hair lower: no flicker where it touches)
  g.center = ((P * up).minCoeff() - 2e-3 * size) * up + g.mid.x() * g.e1 + g.mid.y() * g.e2;
  g.half = 1.5 * size;
  g.spacing = std::pow(10.0, std::floor(std::log10(size / 4)));
  g.margin = 0.5 * ((cage_hi - cage_lo) - (model_hi - model_lo)).cwiseMax(0.0);
  g.shadow_soft = 0.1 * size;
  g.background = kBackground;
  return g;
}

void cast_shadow(Ground& g, const Eigen::MatrixXd& X) {
  // the control mesh's footprint less its margin around the model, a little inside (the fade
  // adds the rest)
  Eigen::Vector2d lo, hi;
  footprint(X, g, lo, hi);
  g.shadow_center = 0.5 * (lo + hi) - g.mid;
  g.shadow_half = (0.5 * (hi - lo) - g.margin - Eigen::Vector2d::Constant(0.25 * g.shadow_soft)).cwiseMax(0.0);
}

Eigen::Matrix3d view_rotation(const Camera& camera) {
  Eigen::Matrix3d rotation;
  rotation.row(0) = camera.right().transpose();
  rotation.row(1) = camera.up().transpose();
  rotation.row(2) = (-camera.direction()).transpose();
  return rotation;
}

}  // namespace mbi::viewer
