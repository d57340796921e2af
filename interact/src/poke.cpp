// The poke spring and the drag plane (poke.hpp).
#include <mbi/interact/error.hpp>
#include <mbi/interact/poke.hpp>
#include <mbi/interp/embed.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace mbi::interact {

double poke_stiffness(double mass, double response) {
  const double w = 2 * std::acos(-1.0) / std::max(response, 1e-6);
  return std::max(mass, 0.0) * w * w;
}

Eigen::Vector3d poke_target(const Ray& ray, const Eigen::Vector3d& grab, const Eigen::Vector3d& normal,
                            double max_distance) {
  if (!ray.direction.allFinite() || ray.direction.squaredNorm() == 0)
    throw Error("poke_target: the ray's direction is zero or not finite");
  if (!normal.allFinite() || normal.squaredNorm() == 0)
    throw Error("poke_target: the plane's normal is zero or not finite");
  if (!grab.allFinite()) throw Error("poke_target: the grabbed point is not finite");
  if (!(max_distance >= 0)) throw Error("poke_target: max_distance must be >= 0");
  const Eigen::Vector3d n = normal.normalized();
  const double denom = ray.direction.dot(n);
  Eigen::Vector3d p = grab;
  if (std::abs(denom) > 1e-12 * ray.direction.norm()) {  // not parallel, whatever the ray's length
    const double t = (grab - ray.origin).dot(n) / denom;
    if (std::isfinite(t)) p = ray.origin + t * ray.direction;
  }
  if (!p.allFinite()) return grab;
  const Eigen::Vector3d d = p - grab;
  const double len = d.norm();
  if (len > max_distance && len > 0) p = grab + d * (max_distance / len);
  return p;
}

Grab grab(const Hit& hit, const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F,
          const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
          const Eigen::Ref<const Eigen::VectorXd>& masses, double response) {
  if (V.cols() != 3 || F.cols() != 3) throw Error("grab: V and F need 3 columns");
  if (hit.face < 0 || hit.face >= F.rows())
    throw Error("grab: face " + std::to_string(hit.face) + " is not a row of F (" + std::to_string(F.rows()) + " rows)");
  if (F.row(hit.face).minCoeff() < 0 || F.row(hit.face).maxCoeff() >= V.rows())
    throw Error("grab: face " + std::to_string(hit.face) + " indexes vertices outside V");
  if (T.cols() != 4) throw Error("grab: T needs 4 columns (tetrahedra), it has " + std::to_string(T.cols()));
  if (masses.size() != U.rows())
    throw Error("grab: " + std::to_string(masses.size()) + " masses for " + std::to_string(U.rows()) + " control vertices");
  // the material point under the cursor: its rest position, then its control element
  Eigen::Vector3d rest = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) rest += hit.bary(k) * V.row(F(hit.face, k)).transpose();
  const interp::Embedding emb = interp::embed(U, T, rest.transpose());
  Grab g;
  g.element = emb.element(0);
  g.bary = emb.bary.row(0).transpose();
  g.point = hit.point;
  double mass = 0;
  for (int k = 0; k < 4; ++k) mass += masses(T(g.element, k));
  g.stiffness = poke_stiffness(mass, response);
  return g;
}

}  // namespace mbi::interact
