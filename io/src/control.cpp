// The element checks every control-mesh reader makes (control.hpp).
#include "control.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace mbi::io::detail {
namespace {
// Determinant of the element's edge vectors divided by its longest edge (scale-free: no
// overflow or underflow for coordinates anywhere in the readers' range); 0 for a zero-length
// edge set.
double relative_measure(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T, Eigen::Index e) {
  const int d = static_cast<int>(U.cols());
  Eigen::MatrixXd E(d, d);
  for (int k = 0; k < d; ++k) E.col(k) = (U.row(T(e, k + 1)) - U.row(T(e, 0))).transpose();
  const double h = E.cwiseAbs().maxCoeff();
  if (!(h > 0) || !std::isfinite(h)) return 0.0;
  E /= h;
  return E.determinant();
}
}  // namespace

void check_elements(const std::filesystem::path& file, const std::vector<int>& line_of,
                    const Eigen::MatrixXd& U, const Eigen::MatrixXi& T) {
  const int d = static_cast<int>(U.cols());
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    const int ln = line_of.empty() ? 0 : line_of[static_cast<std::size_t>(e)];
    for (int a = 0; a <= d; ++a)
      for (int b = a + 1; b <= d; ++b)
        if (T(e, a) == T(e, b))
          fail(file, ln, "element " + std::to_string(e) + ": vertex " +
                             std::to_string(T(e, a)) + " repeated");
    if (!(std::abs(relative_measure(U, T, e)) > 1e-12))
      fail(file, ln, "element " + std::to_string(e) + ": degenerate (zero " +
                         (d == 3 ? "volume" : "area") + ")");
  }
}

}  // namespace mbi::io::detail
