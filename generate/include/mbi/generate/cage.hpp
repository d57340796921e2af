#pragma once
// Control-mesh ("cage") generation: a coarse simplicial mesh that contains a dense surface.
//
// Method: the dense surface is voxelised on a uniform grid of cell size h (every cell that a
// triangle or a vertex touches, plus the cells enclosed by those, found by a flood fill from
// outside). The union of these closed cells contains every dense vertex. Each cell is split
// into simplices with one consistent Kuhn (Freudenthal) subdivision: 6 tetrahedra per cube in
// 3D (dihedral angles 45, 60 and 90 degrees for cubic cells), 2 right triangles per square in 2D
// (45 and 90 degrees), so the mesh is conforming and has no slivers. Parts of the shape farther
// apart than about two cells stay separate. The cell size is searched (deterministically) so
// that the number of control vertices is as close as possible to the target: first cubic cells,
// then, where the count jumps too coarsely, cells whose edges differ per axis (aspect ratio at
// most 1.6, which keeps every dihedral angle above 30 degrees); within 10% of the target the
// most nearly cubic grid wins.
//
// 2D: when every dense vertex has the same z (e.g. the planar alligator and woody meshes), the
// cage is a 2D triangle mesh in x, y (unless Options::force_3d).
//
// Mesher::TetGen (alternative, 3D only: planar input is treated as with force_3d): the same voxel
// envelope, but only its boundary (the boundary quads of the union of the closed cells, each split
// into two triangles along the diagonal through its lowest corner) is given to TetGen (-p -Y: no
// Steiner points on the boundary, so the union and therefore containment are unchanged; -q with a
// radius-edge bound only, which adds a few interior points). Since few vertices lie inside, the
// same vertex budget buys a finer envelope: the cell size is searched on the TetGen vertex count.
// A TetGen mesh whose smallest dihedral angle is below 5 degrees is rejected (other cell sizes and
// switches are tried); if none qualifies make_cage throws Error.
#include <mbi/base/names.hpp>
#include <mbi/error.hpp>

#include <Eigen/Core>

#include <string>

namespace mbi::generate {

/// Every error of mbi::generate: bad input (empty or non-finite vertices, bad indices, a target
/// out of range, an unknown mesher) or no cage that satisfies the guarantees.
class Error : public mbi::Error {
 public:
  using mbi::Error::Error;
};

enum class Mesher {
  Voxel,   ///< every envelope cell split into 6 Kuhn tetrahedra (default)
  TetGen,  ///< the envelope's boundary tetrahedralised by TetGen
};

/// "voxel", "tetgen": the names in scene files (control.mesher) and of `mbi cage --mesher`.
inline constexpr auto kMesherNames =
    name_table<Mesher>({{Mesher::Voxel, "voxel"}, {Mesher::TetGen, "tetgen"}});

/// kMesherNames' name of m.
const char* mesher_name(Mesher m);
/// Parses a name of kMesherNames; throws Error otherwise.
Mesher parse_mesher(const std::string& name);

struct CageOptions {
  int target_vertices = 200;  ///< desired number of control vertices (>= 8 in 3D, >= 4 in 2D)
  bool force_3d = false;      ///< build tetrahedra even for a planar input
  int search_steps = 48;      ///< number of cell sizes tried around the best estimate
  Mesher mesher = Mesher::Voxel;
};

struct CageResult {
  Eigen::MatrixXd U;            ///< n x d control vertices (d = 3, or 2 for planar input)
  Eigen::MatrixXi T;            ///< m x (d+1) tetrahedra / triangles, positive volume
  double cell_size = 0.0;       ///< longest grid cell edge, in the units of the input
  double min_dihedral_deg = 0;  ///< smallest dihedral angle (2D: smallest triangle angle), deg
  int outside_points = 0;       ///< dense vertices outside the cage (mbi::interp::embed)
  double seconds = 0.0;         ///< wall-clock time of the generation
  Mesher mesher = Mesher::Voxel;  ///< the mesher that built U, T
  std::string tetgen_switches;  ///< TetGen switches of the returned mesh (empty for Voxel)
  int dim() const { return static_cast<int>(U.cols()); }
};

/// Builds a cage around the dense surface V (n x 3, finite), F (t x 3, 0-based; may be empty
/// for a point cloud). Deterministic: the same input and options give the same mesh. Throws
/// Error on bad input (empty V, non-finite coordinates, bad indices, target out of range)
/// and if no cell size contains every vertex (TetGen: or if no
/// TetGen mesh has every dihedral angle >= 5 degrees within 30% of the target vertex count).
CageResult make_cage(const Eigen::Ref<const Eigen::MatrixXd>& V,
                     const Eigen::Ref<const Eigen::MatrixXi>& F, const CageOptions& options = {});

/// True when V (n x 3) is a planar model, 2D in `mbi cage` and `mbi run` unless --force-3d:
/// finite, every z the same, and some extent in x or y (one point, or points all equal, are
/// degenerate, not planar: make_cage says so).
bool is_planar(const Eigen::Ref<const Eigen::MatrixXd>& V);

/// Smallest dihedral angle (degrees) over the tetrahedra T of U (3D), or smallest interior
/// angle over the triangles (2D).
double min_dihedral_angle_deg(const Eigen::Ref<const Eigen::MatrixXd>& U,
                              const Eigen::Ref<const Eigen::MatrixXi>& T);

}  // namespace mbi::generate
