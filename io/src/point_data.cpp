// Point data of VTK files (read_point_data) and positions displaced by one of its fields.
#include "control.hpp"

#include <mbi/io/io.hpp>

namespace mbi::io {

using std::filesystem::path;

PointData read_point_data(const path& file) {
  const std::string ext = lower_extension(file);
  if (ext == ".vtu") return detail::read_vtu_point_data(file);
  if (ext == ".vtk") return detail::read_vtk_point_data(file);
  detail::fail(file, 0, "point fields are read from .vtu and .vtk files, not '" + ext + "'");
}

Eigen::MatrixXd read_positions(const path& file, const std::string& displacement) {
  if (displacement.empty()) return read_positions(file);
  const std::string field = "point field '" + displacement + "'";
  const std::string ext = lower_extension(file);
  if (ext != ".vtu" && ext != ".vtk")
    detail::fail(file, 0, "no " + field + ": displacement fields are read from .vtu and .vtk files");
  PointData d = read_point_data(file);
  std::string names;
  for (const PointField& f : d.fields) {
    names += (names.empty() ? "" : ", ") + f.name;
    if (f.name != displacement) continue;
    const Eigen::Index n = d.P.rows(), c = f.values.cols();
    if (f.values.rows() != n || (c != 2 && c != 3))
      detail::fail(file, 0, field + ": " + std::to_string(f.values.rows()) + " x " + std::to_string(c) +
                                " values, a displacement of the " + std::to_string(n) + " points is " + std::to_string(n) +
                                " x 3 (or x 2)");
    if (!f.values.allFinite()) detail::fail(file, 0, field + ": non-finite value");
    d.P.leftCols(c) += f.values;
    return d.P;
  }
  detail::fail(file, 0, "no " + field + " (point fields: " + (names.empty() ? "none" : names) + ")");
}

}  // namespace mbi::io
