#pragma once
// What the control-mesh formats (format_tetgen/gmsh/vtk.cpp) share.
#include "io_common.hpp"

#include <vector>

namespace mbi::io::detail {

/// Rejects repeated vertices and zero-volume elements (relative to the longest edge): the
/// message names element e and line_of[e] (no line when line_of is empty).
void check_elements(const std::filesystem::path& file, const std::vector<int>& line_of,
                    const Eigen::MatrixXd& U, const Eigen::MatrixXi& T);

/// BASE`ext` for a TetGen name: `base` without its .node/.ele/.face extension, if it has one.
std::filesystem::path tetgen_file(const std::filesystem::path& base, const char* ext);
/// The files read_tetgen(base) reads: BASE.node and BASE.ele.
std::vector<std::filesystem::path> tetgen_files(const std::filesystem::path& base);

}  // namespace mbi::io::detail
