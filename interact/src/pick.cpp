// Picking (pick.hpp).
#include <mbi/interact/error.hpp>
#include <mbi/interact/pick.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <string>

namespace mbi::interact {
namespace {

void check_ray(const Ray& ray, const char* where) {
  if (!ray.direction.allFinite() || ray.direction.squaredNorm() == 0)
    throw Error(std::string(where) + ": the ray's direction is zero or not finite");
  if (!ray.origin.allFinite()) throw Error(std::string(where) + ": the ray's origin is not finite");
}

void check_mesh(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F) {
  if (V.cols() != 3 || F.cols() != 3)
    throw Error("cast: V and F need 3 columns (V has " + std::to_string(V.cols()) + ", F " +
                std::to_string(F.cols()) + ")");
  if (F.rows() == 0) throw Error("cast: the mesh has no triangles");
  if (F.minCoeff() < 0 || F.maxCoeff() >= V.rows())
    throw Error("cast: F indexes vertices outside V's " + std::to_string(V.rows()) + " rows");
}

}  // namespace

std::optional<Hit> cast(const Ray& ray, const Eigen::Ref<const Eigen::MatrixXd>& V,
                        const Eigen::Ref<const Eigen::MatrixXi>& F, double slack) {
  check_ray(ray, "cast");
  check_mesh(V, F);
  if (!(slack >= 0)) throw Error("cast: slack must be >= 0");
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

}  // namespace mbi::interact
