// The only file that includes OpenVDB (its headers compile slowly).
#include <mbi/error.hpp>
#include <mbi/pipeline/mesh_level_set.hpp>
#include <mbi/sim/rigid_pose.hpp>

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>

namespace mbi::pipeline {
namespace {

[[noreturn]] void bad(const std::string& what) { throw Error("MeshLevelSet: " + what); }

std::string edge_text(int a, int b) { return "(" + std::to_string(a) + ", " + std::to_string(b) + ")"; }

void check_vertices(const Eigen::Ref<const Eigen::MatrixXd>& V) {
  if (V.cols() != 3) bad("vertices must be n x 3, got " + std::to_string(V.rows()) + " x " + std::to_string(V.cols()));
  if (V.rows() == 0) bad("vertices is empty");
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    if (!V.row(i).allFinite()) bad("vertices: vertex " + std::to_string(i) + " is not finite");
}

void check_triangles(const Eigen::Ref<const Eigen::MatrixXi>& F, Eigen::Index vertex_count) {
  if (F.cols() != 3) bad("triangles must be m x 3, got " + std::to_string(F.rows()) + " x " + std::to_string(F.cols()));
  if (F.rows() == 0) bad("triangles is empty");
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int v = F(t, k);
      if (v < 0 || v >= vertex_count)
        bad("triangles: triangle " + std::to_string(t) + " has vertex index " + std::to_string(v) +
            " out of range [0, " + std::to_string(vertex_count) + ")");
      if (F(t, (k + 1) % 3) == v) bad("triangles: triangle " + std::to_string(t) + " repeats vertex " + std::to_string(v));
    }
}

std::uint64_t edge_key(int a, int b) {
  return (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
}

/// Closed: every edge is used by an even number of triangles (2 for a manifold).
void check_closed(const Eigen::Ref<const Eigen::MatrixXi>& F) {
  std::unordered_map<std::uint64_t, int> uses;
  uses.reserve(std::size_t(F.rows()) * 3);
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int k = 0; k < 3; ++k) ++uses[edge_key(F(t, k), F(t, (k + 1) % 3))];
  long open = 0;
  for (const auto& [key, n] : uses) open += n % 2;
  if (open == 0) return;
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = F(t, k), b = F(t, (k + 1) % 3);
      if (uses[edge_key(a, b)] % 2)
        bad("triangles: the mesh is not closed: " + std::to_string(open) +
            " boundary edges (used by an odd number of triangles), the first " + edge_text(a, b) +
            " of triangle " + std::to_string(t));
    }
}

double checked_voxel_size(const MeshLevelSetOptions& o, const Eigen::Vector3d& extent, double default_h) {
  if (!std::isfinite(o.band_voxels) || o.band_voxels < 1)
    bad("band_voxels must be finite and >= 1, got " + std::to_string(o.band_voxels));
  const double h = o.voxel_size.value_or(default_h);
  if (!std::isfinite(h) || h <= 0) bad("voxel_size must be finite and > 0 m, got " + std::to_string(h));
  const Eigen::Array3d cells = extent.array() / h + 2 * o.band_voxels + 2;
  if (cells.prod() > double(1 << 27))
    bad("voxel_size " + std::to_string(h) + " m is too small for the mesh: " + std::to_string(cells.prod()) +
        " voxels in its bounding box (at most 2^27)");
  return h;
}

Eigen::AlignedBox3d bounding_box(const Eigen::Ref<const Eigen::MatrixXd>& V) {
  return Eigen::AlignedBox3d(V.colwise().minCoeff().transpose(), V.colwise().maxCoeff().transpose());
}

}  // namespace

struct MeshLevelSet::Grid {
  openvdb::FloatGrid::Ptr grid;
  Eigen::AlignedBox3d bounds;  // m, the mesh's frame; the grid's origin is bounds.min()
  Eigen::MatrixXd vertices;    // the mesh as given, for drawing
  Eigen::MatrixXi triangles;
  double h = 0.0;
  double band_voxels = 0.0;
  Eigen::Vector3d lo, hi;  // index coordinates beyond which no voxel is resolved
  double lipschitz = 1.0;

  LevelSetSample local(const Eigen::Vector3d& p) const;
  LevelSetSample outside(const Eigen::Vector3d& p) const;
  double steepest() const;
};

// In a cell the trilinear interpolant's derivative along an axis is a weighted mean of the cell's
// four differences along that axis, so per cell |gradient| <= the norm of the three largest;
// the bound is the largest over every cell with a stored corner (the others read the
// background, as sample() reads them: flat). Outside the band the value is 1-Lipschitz.
double MeshLevelSet::Grid::steepest() const {
  auto acc = grid->getConstAccessor();
  double most = 1.0;
  double v[3][3][3];
  for (auto it = grid->cbeginValueOn(); it; ++it) {
    const openvdb::Coord c = it.getCoord();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) v[i][j][k] = acc.getValue(c.offsetBy(i - 1, j - 1, k - 1));
    for (int ci = 0; ci < 2; ++ci)  // the 8 cells with c as a corner
      for (int cj = 0; cj < 2; ++cj)
        for (int ck = 0; ck < 2; ++ck) {
          Eigen::Vector3d d = Eigen::Vector3d::Zero();
          for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b) {
              d.x() = std::max(d.x(), std::abs(v[ci + 1][cj + a][ck + b] - v[ci][cj + a][ck + b]));
              d.y() = std::max(d.y(), std::abs(v[ci + a][cj + 1][ck + b] - v[ci + a][cj][ck + b]));
              d.z() = std::max(d.z(), std::abs(v[ci + a][cj + b][ck + 1] - v[ci + a][cj + b][ck]));
            }
          most = std::max(most, d.norm() / h);
        }
  }
  return most;
}

double MeshLevelSet::default_voxel_size(const Eigen::Ref<const Eigen::MatrixXd>& vertices) {
  check_vertices(vertices);
  return bounding_box(vertices).diagonal().norm() / 128.0;
}

MeshLevelSet::MeshLevelSet(const Eigen::Ref<const Eigen::MatrixXd>& vertices,
                           const Eigen::Ref<const Eigen::MatrixXi>& triangles, const MeshLevelSetOptions& options) {
  check_vertices(vertices);
  check_triangles(triangles, vertices.rows());
  check_closed(triangles);
  auto g = std::make_shared<Grid>();
  g->bounds = bounding_box(vertices);
  g->vertices = vertices;
  g->triangles = triangles;
  const Eigen::Vector3d extent = g->bounds.diagonal();
  if (extent.norm() == 0) bad("vertices: the mesh has zero extent (all vertices coincide)");
  g->h = checked_voxel_size(options, extent, extent.norm() / 128.0);
  g->band_voxels = options.band_voxels;
  const double reach = options.band_voxels + 2;
  g->lo = Eigen::Vector3d::Constant(-reach);
  g->hi = extent / g->h + Eigen::Vector3d::Constant(reach);

  openvdb::initialize();
  std::vector<openvdb::Vec3s> points(std::size_t(vertices.rows()));
  for (Eigen::Index i = 0; i < vertices.rows(); ++i) {
    const Eigen::Vector3d q = (vertices.row(i).transpose() - g->bounds.min()) / g->h;  // index space
    points[std::size_t(i)] = openvdb::Vec3s(float(q.x()), float(q.y()), float(q.z()));
  }
  std::vector<openvdb::Vec3I> tris(std::size_t(triangles.rows()));
  for (Eigen::Index t = 0; t < triangles.rows(); ++t)
    tris[std::size_t(t)] = openvdb::Vec3I(openvdb::Index32(triangles(t, 0)), openvdb::Index32(triangles(t, 1)),
                                          openvdb::Index32(triangles(t, 2)));
  const openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> mesh(points, tris);
  const auto xform = openvdb::math::Transform::createLinearTransform(g->h);
  // interior band: everything, so that a point deep inside still gets its way out
  g->grid = openvdb::tools::meshToVolume<openvdb::FloatGrid>(mesh, *xform, float(options.band_voxels),
                                                             std::numeric_limits<float>::max());
  g->lipschitz = g->steepest();
  grid_ = std::move(g);
}

LevelSetSample MeshLevelSet::Grid::outside(const Eigen::Vector3d& p) const {
  LevelSetSample s;
  s.in_band = false;
  const Eigen::Vector3d below = bounds.min() - p, above = p - bounds.max();
  const Eigen::Vector3d out = below.cwiseMax(above).cwiseMax(0.0);
  const double box = out.norm();
  if (box > 0) {
    s.normal = (above.array() > 0).select(out, -out) / box;
  } else {
    const Eigen::Vector3d from_centre = p - bounds.center();
    if (from_centre.norm() > 0) s.normal = from_centre.normalized();
  }
  const double band = band_voxels * h;
  s.value = std::max(band, box);
  if (box > band) s.gradient = s.normal;
  return s;
}

LevelSetSample MeshLevelSet::Grid::local(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d x = (p - bounds.min()) / h;  // index coordinates: voxel centres at integers
  if ((x.array() < lo.array()).any() || (x.array() > hi.array()).any()) return outside(p);
  const Eigen::Vector3d base = x.array().floor();
  const Eigen::Vector3d f = x - base;
  const openvdb::Coord c0(int(base.x()), int(base.y()), int(base.z()));
  auto acc = grid->getConstUnsafeAccessor();  // one per call: the caching accessors are not shared
  LevelSetSample s;
  s.value = 0.0;
  bool resolved = false;
  for (int corner = 0; corner < 8; ++corner) {
    const int a = corner & 1, b = (corner >> 1) & 1, c = (corner >> 2) & 1;
    float value = 0.0f;
    resolved |= acc.probeValue(c0.offsetBy(a, b, c), value);
    const double wx = a ? f.x() : 1 - f.x(), wy = b ? f.y() : 1 - f.y(), wz = c ? f.z() : 1 - f.z();
    const double dx = a ? 1.0 : -1.0, dy = b ? 1.0 : -1.0, dz = c ? 1.0 : -1.0;
    s.value += wx * wy * wz * value;
    s.gradient += double(value) * Eigen::Vector3d(dx * wy * wz, wx * dy * wz, wx * wy * dz);
  }
  if (!resolved && s.value >= 0) return outside(p);
  s.gradient /= h;
  const double len = s.gradient.norm();
  if (len > 0) s.normal = s.gradient / len;
  return s;
}

LevelSetSample MeshLevelSet::sample(const Eigen::Vector3d& p) const {
  if (!p.allFinite()) bad("sample: the point is not finite");
  return grid_->local(p);
}

LevelSetSample MeshLevelSet::sample(const Eigen::Vector3d& p, const sim::RigidMotion& motion, double time) const {
  if (!p.allFinite() || !std::isfinite(time)) bad("sample: the point or the time is not finite");
  const sim::RigidPose ps = sim::rigid_pose(motion, time);
  LevelSetSample out = grid_->local(motion.center + ps.rot.transpose() * (p - ps.shift));
  out.gradient = ps.rot * out.gradient;
  out.normal = ps.rot * out.normal;
  return out;
}

double MeshLevelSet::voxel_size() const { return grid_->h; }
double MeshLevelSet::band() const { return grid_->band_voxels * grid_->h; }
const Eigen::AlignedBox3d& MeshLevelSet::bounds() const { return grid_->bounds; }
const Eigen::MatrixXd& MeshLevelSet::vertices() const { return grid_->vertices; }
const Eigen::MatrixXi& MeshLevelSet::triangles() const { return grid_->triangles; }
long MeshLevelSet::active_voxels() const { return long(grid_->grid->activeVoxelCount()); }
double MeshLevelSet::lipschitz() const { return grid_->lipschitz; }

}  // namespace mbi::pipeline
