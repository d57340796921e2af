// Colliders as triangles at their pose (collider_mesh.hpp).
#include <mbi/pipeline/collider_mesh.hpp>
#include <mbi/error.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <string>
#include <utility>

namespace mbi::pipeline {
namespace {

// Two unit vectors that make (e1, e2, n) an orthonormal frame, n unit.
void perpendiculars(const Eigen::Vector3d& n, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
  const Eigen::Vector3d side = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1 = side.cross(n).normalized();
  e2 = n.cross(e1);
}

// Each triangle turned so that its winding agrees with its vertices' outward normals.
void orient(ColliderMesh& m) {
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Eigen::Vector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    const Eigen::Vector3d n = m.N.row(m.F(f, 0)) + m.N.row(m.F(f, 1)) + m.N.row(m.F(f, 2));
    if ((b - a).cross(c - a).dot(n) < 0) std::swap(m.F(f, 1), m.F(f, 2));
  }
}

// The points within `radius` of the segment [a, b] (a sphere when a = b): 16 latitudes about
// the axis, the two half spheres joined by the cylinder between their equators.
ColliderMesh rounded(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius) {
  const int lat = 16, lon = 32;
  const double pi = std::acos(-1.0);
  const Eigen::Vector3d axis = (b - a).norm() > 0 ? Eigen::Vector3d((b - a).normalized()) : Eigen::Vector3d::UnitY();
  Eigen::Vector3d e1, e2;
  perpendiculars(axis, e1, e2);
  const int rings = lat + 2;  // the equator twice: once on each half sphere
  ColliderMesh m;
  m.V.resize(rings * lon, 3);
  m.N.resize(rings * lon, 3);
  for (int r = 0; r < rings; ++r) {
    const int k = r <= lat / 2 ? r : r - 1;  // latitude index, 0 at b's pole
    const double theta = pi * k / lat;
    const Eigen::Vector3d& center = r <= lat / 2 ? b : a;
    for (int j = 0; j < lon; ++j) {
      const double phi = 2 * pi * j / lon;
      const Eigen::Vector3d n = std::sin(theta) * (std::cos(phi) * e1 + std::sin(phi) * e2) + std::cos(theta) * axis;
      m.N.row(r * lon + j) = n.transpose();
      m.V.row(r * lon + j) = (center + radius * n).transpose();
    }
  }
  m.F.resize(2 * (rings - 1) * lon, 3);
  for (int r = 0, f = 0; r + 1 < rings; ++r)
    for (int j = 0; j < lon; ++j) {
      const int p = r * lon + j, q = r * lon + (j + 1) % lon;
      m.F.row(f++) << p, q, q + lon;
      m.F.row(f++) << p, q + lon, p + lon;
    }
  orient(m);
  return m;
}

// A box about `center` with half extents `half` along the unit columns of `axes`: four vertices a face.
ColliderMesh box(const Eigen::Vector3d& center, const Eigen::Vector3d& half, const Eigen::Matrix3d& axes) {
  ColliderMesh m;
  m.V.resize(24, 3);
  m.N.resize(24, 3);
  m.F.resize(12, 3);
  int v = 0, f = 0;
  for (int k = 0; k < 3; ++k)
    for (double s : {-1.0, 1.0}) {
      const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
      const Eigen::Vector3d n = s * axes.col(k), mid = center + half(k) * n;
      const Eigen::Vector3d u = half(k1) * axes.col(k1), w = half(k2) * axes.col(k2);
      const Eigen::Vector3d corners[4] = {mid - u - w, mid + u - w, mid + u + w, mid - u + w};
      for (const Eigen::Vector3d& c : corners) m.V.row(v) = c.transpose(), m.N.row(v++) = n.transpose();
      m.F.row(f++) << v - 4, v - 3, v - 2;
      m.F.row(f++) << v - 4, v - 2, v - 1;
    }
  orient(m);
  return m;
}

// A mesh collider's triangles at its pose (world = point + axes local), a vertex a corner with
// its triangle's normal (flat faces; the winding's side, which for a level set's mesh may be in).
ColliderMesh placed(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const Eigen::Vector3d& point,
                    const Eigen::Matrix3d& axes) {
  ColliderMesh m;
  m.V.resize(3 * F.rows(), 3);
  m.N.resize(3 * F.rows(), 3);
  m.F.resize(F.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    Eigen::Vector3d p[3];
    for (int k = 0; k < 3; ++k) p[k] = point + axes * V.row(F(f, k)).transpose();
    Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
    if (!n.allFinite()) n = Eigen::Vector3d::UnitZ();  // a degenerate triangle
    for (int k = 0; k < 3; ++k) {
      m.V.row(3 * f + k) = p[k].transpose();
      m.N.row(3 * f + k) = n.transpose();
      m.F(f, k) = static_cast<int>(3 * f + k);
    }
  }
  return m;
}

ColliderMesh square(const Collider& c, const ColliderMeshOptions& o) {
  const Eigen::Vector3d n = c.normal.normalized();
  const Eigen::Vector3d mid = o.plane_center - n.dot(o.plane_center - c.point) * n;
  Eigen::Vector3d e1, e2;
  perpendiculars(n, e1, e2);
  const Eigen::Vector3d u = o.plane_half * e1, w = o.plane_half * e2;
  ColliderMesh m;
  m.V.resize(4, 3);
  m.V << (mid - u - w).transpose(), (mid + u - w).transpose(), (mid + u + w).transpose(), (mid - u + w).transpose();
  m.N = n.transpose().replicate(4, 1);
  m.F.resize(2, 3);
  m.F << 0, 1, 2, 0, 2, 3;
  orient(m);
  return m;
}

}  // namespace

ColliderMesh collider_mesh(const Collider& collider, double time, const ColliderMeshOptions& options) {
  if (!std::isfinite(options.plane_half) || options.plane_half <= 0)
    throw Error("collider_mesh: plane_half must be finite and > 0, got " + std::to_string(options.plane_half));
  if (!options.plane_center.allFinite()) throw Error("collider_mesh: plane_center is not finite");
  const Collider c = posed(collider, time);
  switch (c.shape) {
    case ColliderShape::Plane: return square(c, options);
    case ColliderShape::Sphere: return rounded(c.point, c.point, c.radius);
    case ColliderShape::Capsule: return rounded(c.point, c.end, c.radius);
    case ColliderShape::Box: return box(c.point, c.half_extents, c.axes);
    case ColliderShape::Mesh:
      if (!c.level_set) throw Error("collider_mesh: a mesh collider without a level set");
      return placed(c.level_set->vertices(), c.level_set->triangles(), c.point, c.axes);
  }
  throw Error("collider_mesh: unknown collider shape");
}

}  // namespace mbi::pipeline
