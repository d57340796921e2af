// The colliders and the ground of the 3D pictures (picture_colliders.hpp).
#include "picture_colliders.hpp"

#include <mbi/pipeline/collider_mesh.hpp>
#include <mbi/pipeline/driver.hpp>

#include <algorithm>
#include <cmath>

namespace mbi::scenes {
namespace {

using pipeline::Collider;
using pipeline::ColliderShape;

const pipeline::SimulatorDriver* simulator_of(pipeline::FramePipeline& pipe) {
  return dynamic_cast<const pipeline::SimulatorDriver*>(&pipe.driver());
}

constexpr int kCorners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};  // a cell's, counter-clockwise

// The square of a plane as cells x cells squares in two alternating greys (the light first).
std::vector<raster::Solid> checked(const Eigen::MatrixXd& corners, int cells) {
  raster::Solid light{{}, {}, {0.93, 0.93, 0.93}, false}, dark{{}, {}, {0.84, 0.84, 0.84}, false};
  for (raster::Solid* s : {&light, &dark}) {
    s->V.resize(4 * cells * cells, 3);  // room for every cell; cut to size below
    s->F.resize(2 * cells * cells, 3);
  }
  const Eigen::RowVector3d o = corners.row(0), a = corners.row(1) - o, b = corners.row(3) - o;
  int v[2] = {0, 0};
  for (int i = 0; i < cells; ++i)
    for (int j = 0; j < cells; ++j) {
      const int k = (i + j) % 2;
      raster::Solid& s = k ? dark : light;
      const int first = v[k];
      for (const auto& d : kCorners) s.V.row(v[k]++) = o + (double(i + d[0]) / cells) * a + (double(j + d[1]) / cells) * b;
      const int f = first / 2;
      s.F.row(f) << first, first + 1, first + 2;
      s.F.row(f + 1) << first, first + 2, first + 3;
    }
  for (int k = 0; k < 2; ++k) {
    raster::Solid& s = k ? dark : light;
    s.V.conservativeResize(v[k], 3);
    s.F.conservativeResize(v[k] / 2, 3);
  }
  return {light, dark};
}

// Half the side of a plane's square about `center` that keeps the square within the depth range
// a GPU picture of `view` draws (the bounds' depth range, half of it again each side), at most
// `largest`; 0 when the plane lies outside that range there.
double square_half(const Collider& plane, const Eigen::Vector3d& center, const raster::View& view, double largest) {
  const Eigen::Vector3d f = view.direction.normalized(), n = plane.normal.normalized();
  double z0 = 1e300, z1 = -1e300;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p((c & 1) ? view.bounds_max.x() : view.bounds_min.x(),
                            (c & 2) ? view.bounds_max.y() : view.bounds_min.y(),
                            (c & 4) ? view.bounds_max.z() : view.bounds_min.z());
    z0 = std::min(z0, p.dot(f)), z1 = std::max(z1, p.dot(f));
  }
  const double reach = 0.45 * (z1 - z0);  // within the GPU's half range of padding
  const double z = (center - n.dot(center - plane.point) * n).dot(f);
  const double room = std::min(z1 + reach - z, z - z0 + reach);
  const double spread = std::sqrt(std::max(0.0, 2 * (1 - n.dot(f) * n.dot(f))));  // depth per unit of half side
  if (room <= 0) return 0;
  return spread > 1e-12 ? std::min(largest, room / spread) : largest;
}

}  // namespace

std::vector<Collider> picture_colliders(pipeline::FramePipeline& pipe) {
  const pipeline::SimulatorDriver* sim = simulator_of(pipe);
  if (!sim) return {};
  if (sim->contact()) return sim->contact()->colliders();
  const sim::Parameters& p = sim->simulator().params();
  if (!p.ground) return {};
  const Eigen::Vector3d n = p.ground_plane.normal.normalized();
  return {Collider::plane(p.ground_plane.offset / p.ground_plane.normal.norm() * n, n)};
}

double picture_time(pipeline::FramePipeline& pipe) {
  const pipeline::SimulatorDriver* sim = simulator_of(pipe);
  return sim ? sim->simulator().time() : 0.0;
}

Eigen::AlignedBox3d near_bounds(const std::vector<Collider>& colliders, double time, const Eigen::AlignedBox3d& model) {
  Eigen::AlignedBox3d near;  // empty
  if (model.isEmpty()) return near;
  const Eigen::Vector3d grow = Eigen::Vector3d::Constant(0.5 * model.sizes().maxCoeff());
  const Eigen::AlignedBox3d around(model.min() - grow, model.max() + grow);
  for (const Collider& c : colliders) {
    if (c.shape == ColliderShape::Plane) continue;
    const pipeline::ColliderMesh m = pipeline::collider_mesh(c, time);
    if (m.V.rows() == 0) continue;
    const Eigen::AlignedBox3d box(m.V.colwise().minCoeff().transpose(), m.V.colwise().maxCoeff().transpose());
    const Eigen::AlignedBox3d part = box.intersection(around);
    if (!part.isEmpty()) near.extend(part);
  }
  return near;
}

std::vector<raster::Solid> picture_solids(const std::vector<Collider>& colliders, double time, const raster::View& view) {
  std::vector<raster::Solid> solids;
  for (const Collider& c : colliders)
    if (c.shape != ColliderShape::Plane) {
      const pipeline::ColliderMesh m = pipeline::collider_mesh(c, time);
      solids.push_back({m.V, m.F, kColliderColor});
    }
  const Eigen::Vector3d center = 0.5 * (view.bounds_min + view.bounds_max);
  const double largest = 1.5 * (view.bounds_max - view.bounds_min).maxCoeff();
  for (const Collider& c : colliders) {
    if (c.shape != ColliderShape::Plane) continue;
    const double half = square_half(pipeline::posed(c, time), center, view, largest);
    if (!(half > 0)) continue;
    pipeline::ColliderMesh m = pipeline::collider_mesh(c, time, {.plane_half = half, .plane_center = center});
    // a hair under the plane, so that a collider's face on it (a step's tread on the floor) wins
    m.V.rowwise() -= (2e-3 * largest * pipeline::posed(c, time).normal.normalized()).transpose();
    for (raster::Solid& s : checked(m.V, 12)) solids.push_back(std::move(s));
  }
  return solids;
}

}  // namespace mbi::scenes
