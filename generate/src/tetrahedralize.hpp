#pragma once
// TetGen behind one call, for the cage's TetGen mesher (cage.cpp). tetrahedralize.cpp runs it;
// without_tetgen.cpp stands in where the build has no TetGen (MBI_WITH_TETGEN=OFF, as in the
// browser build), and make_cage then refuses Mesher::TetGen.
#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace mbi::generate::detail {

/// False in a build without TetGen.
bool have_tetgen();

/// Tetrahedralises the closed triangle surface X (b x 3 points), B (facets, 0-based) with
/// TetGen's `switches`: points (n x 3, X's first when the switches keep the boundary) and tets
/// (t x 4, 0-based, as TetGen returns them). False with the reason in `why` when TetGen fails
/// or returns no tetrahedra.
bool tetrahedralize(const Eigen::MatrixXd& X, const std::vector<std::array<int, 3>>& B,
                    const std::string& switches, Eigen::MatrixXd& points, Eigen::MatrixXi& tets,
                    std::string& why);

}  // namespace mbi::generate::detail
