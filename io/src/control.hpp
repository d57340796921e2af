#pragma once
// What the control-mesh formats (format_tetgen/gmsh/vtk.cpp) share.
#include "io_common.hpp"

#include <vector>

namespace mbi::io::detail {

/// Rejects repeated vertices and zero-volume elements (relative to the longest edge): the
/// message names element e and line_of[e] (no line when line_of is empty).
void check_elements(const std::filesystem::path& file, const std::vector<int>& line_of,
                    const Eigen::MatrixXd& U, const Eigen::MatrixXi& T);

/// One cell of a VTK unstructured grid (legacy .vtk or XML .vtu): its VTK cell type and points.
struct VtkCell {
  int type;
  std::vector<long long> nodes;
};
/// The control mesh of a VTK unstructured grid's points (n x 3) and cells: tetrahedra (type 10,
/// quadratic 24 by its corners) make a 3D mesh, else triangles (5, 22) a 2D one (z constant,
/// dropped); other cells are skipped (named when nothing usable is left). Point indices are
/// checked by the caller.
ControlMesh vtk_control_mesh(const Eigen::MatrixXd& P, const std::vector<VtkCell>& cells,
                             const std::filesystem::path& file);

/// read_point_data of a .vtu and of a legacy .vtk file.
PointData read_vtu_point_data(const std::filesystem::path& file);
PointData read_vtk_point_data(const std::filesystem::path& file);

/// BASE`ext` for a TetGen name: `base` without its .node/.ele/.face extension, if it has one.
std::filesystem::path tetgen_file(const std::filesystem::path& base, const char* ext);
/// The files read_tetgen(base) reads: BASE.node and BASE.ele.
std::vector<std::filesystem::path> tetgen_files(const std::filesystem::path& base);

}  // namespace mbi::io::detail
