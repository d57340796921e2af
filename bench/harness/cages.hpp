#pragma once
// The harness's own test geometry (it uses nothing of mbi but the installed public API): box
// control meshes of unit cells, 6 tetrahedra a cell, a twisted and bent pose of them, and random
// dense points inside.
#include <Eigen/Core>

namespace harness {

struct Cage {
  Eigen::MatrixXd U;  ///< n x 3 rest vertices
  Eigen::MatrixXi T;  ///< m x 4 positively oriented tetrahedra
  Eigen::Vector3i cells;
};

/// nx x ny x nz cells: (nx+1)(ny+1)(nz+1) vertices (7x7x6: 448; 10x10x10: 1,331).
Cage box(int nx, int ny, int nz);

/// The rest vertices twisted about the box's vertical axis by `turn` radians over its height and
/// bent sideways; `phase` in [0, 1] scales both (a frame loop's frames differ).
Eigen::MatrixXd pose(const Cage& c, double phase);

/// p points uniformly random inside the box (seeded: every run the same points).
Eigen::MatrixXd cloud(const Cage& c, long long p);

}  // namespace harness
