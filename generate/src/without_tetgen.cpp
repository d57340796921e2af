// The stand-in for tetrahedralize.cpp in a build without TetGen (MBI_WITH_TETGEN=OFF).
#include "tetrahedralize.hpp"

namespace mbi::generate::detail {

bool have_tetgen() { return false; }

bool tetrahedralize(const Eigen::MatrixXd&, const std::vector<std::array<int, 3>>&,
                    const std::string&, Eigen::MatrixXd&, Eigen::MatrixXi&, std::string& why) {
  why = "this build has no TetGen";
  return false;
}

}  // namespace mbi::generate::detail
