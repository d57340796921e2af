#pragma once
// A closed triangle mesh as a signed distance field: OpenVDB's mesh-to-level-set conversion
// (docs/mesh-colliders.md), sampled trilinearly with the gradient of the interpolant. The
// OpenVDB grid stays inside the implementation; this header needs Eigen only.
//
//   MeshLevelSet steps(V, F);                       // V: n x 3 (m), F: m x 3 vertex indices
//   LevelSetSample s = steps.sample(p);             // p in the mesh's own frame (m)
//   LevelSetSample w = steps.sample(p, motion, t);  // the mesh moved by a sim::RigidMotion
//
// Sign: negative inside. Inside is what cannot be reached from outside the mesh without crossing
// it (OpenVDB's flood fill of the voxels the triangles cut), so triangle orientation does not
// matter, overlapping closed parts give their union, and closed cavities are solid.
#include <mbi/sim/simulator.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <optional>

namespace mbi::pipeline {

struct MeshLevelSetOptions {
  /// Voxel edge h (m, finite, > 0); default: `default_voxel_size`. Refused when the bounding box
  /// grown by the band would hold more than 2^27 voxels.
  std::optional<double> voxel_size;
  /// Exterior narrow band, in voxels (finite, >= 1): distances are resolved up to band h
  /// outside the mesh. The interior is resolved everywhere.
  double band_voxels = 3.0;
};

struct LevelSetSample {
  double value = 0.0;                                ///< m, signed: < 0 inside
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();  ///< d value / d p (|.| about 1 in the band)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();   ///< unit gradient (outward)
  bool in_band = true;  ///< false: the conservative value outside the band (below)
};

/// The signed distance field of a closed triangle mesh, immutable once built. Copies share the
/// grid. Threading: every const member may be called from any number of threads at once (each
/// sample reads the grid through its own accessor); construction runs on TBB's threads.
class MeshLevelSet {
 public:
  /// vertices: n x 3 rest positions (m); triangles: m x 3 indices into vertices (0-based).
  /// Throws mbi::Error naming the argument and the element: an empty mesh, a wrong column
  /// count, a non-finite vertex, an index out of range, a triangle that repeats a vertex, a mesh
  /// that is not closed (an edge used by an odd number of triangles: the count and the first
  /// such edge with its triangle), a bad option. Self-intersections are accepted (see the sign
  /// rule above). Cost: O(triangles + voxels), on TBB's threads.
  MeshLevelSet(const Eigen::Ref<const Eigen::MatrixXd>& vertices, const Eigen::Ref<const Eigen::MatrixXi>& triangles,
               const MeshLevelSetOptions& options = {});

  /// The default voxel edge (m): the bounding box's diagonal / 128. A box then holds at most
  /// about 74^3 voxels (a cube), and a feature 1/20 of the diagonal thick spans 6 voxels.
  static double default_voxel_size(const Eigen::Ref<const Eigen::MatrixXd>& vertices);

  /// Signed distance (m) at p (m, the mesh's frame) and its gradient, O(1) (8 voxels read): one voxel
  /// accurate, continuous (trilinear) inside the band and the interior; the gradient is the
  /// interpolant's, piecewise constant per voxel direction, so the normal jumps by a few degrees
  /// between voxels. Outside the band (no voxel of p's cell resolved) the value is the larger of
  /// the band (band h) and the distance to the mesh's bounding box, a lower bound of the true
  /// distance within a voxel (safe for conservative advancement), and the normal points away
  /// from the box (its nearest point, or its centre from inside it); in_band is false.
  /// Where the gradient is zero (a medial point) the normal is +x. Throws mbi::Error for a
  /// non-finite p.
  LevelSetSample sample(const Eigen::Vector3d& p) const;
  /// The same for the mesh moved by a rigid motion (the mesh given at its pose at motion.start;
  /// at time t (s) moved by the motion's map of t, as pipeline::Collider's shapes): p and the
  /// returned gradient and normal are in the world frame.
  LevelSetSample sample(const Eigen::Vector3d& p, const sim::RigidMotion& motion, double time) const;

  double voxel_size() const;  ///< h, m
  double band() const;        ///< exterior band width, m (band_voxels h)
  const Eigen::AlignedBox3d& bounds() const;  ///< the mesh's bounding box, m
  const Eigen::MatrixXd& vertices() const;     ///< the mesh as given (m, its frame): to draw it
  const Eigen::MatrixXi& triangles() const;    ///< as given
  long active_voxels() const;  ///< voxels with a resolved distance (memory: 8 to 17 bytes each)
  /// A bound (>= 1) on |gradient| of sample()'s value everywhere: the value changes by at most
  /// lipschitz() |dp| along any segment dp. The stored distances are approximate, so the
  /// trilinear interpolant can be steeper than a true distance (whose bound is 1); measured once
  /// from the largest difference between neighbouring voxels along each axis, O(voxels).
  double lipschitz() const;

 private:
  struct Grid;
  std::shared_ptr<const Grid> grid_;
};

}  // namespace mbi::pipeline
