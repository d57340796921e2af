#pragma once
// Several dense models driven by one control mesh, as one: their points are concatenated (in the
// order given) into one embedding and one evaluation, and each model's rows are cut out again for
// its own output, so the pipeline sees a single point set. Used by mbi cage (the cage encloses
// every part) and mbi deform (several --mesh, each with its --out).
#include <mbi/io/io.hpp>

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace mbi::cli {

struct DensePart {
  std::string file;
  std::optional<io::SurfaceMesh> surface;  ///< none for a point list (.txt, .xyz)
  Eigen::Index first = 0, rows = 0;        ///< its rows in DenseParts::P
  /// Whether its file gave normals (its output then gets deformed normals).
  bool has_normals() const;
};

struct DenseParts {
  std::vector<DensePart> parts;
  Eigen::MatrixXd P;  ///< every part's points, p x c (every part has the same c)
  /// "a.obj" or "a.obj, b.glb" for messages.
  std::string names() const;
  /// The rest normals of all points (p x 3) when some part has normals (the others get the
  /// area-weighted normals of their faces, only to be evaluated with them); else empty.
  Eigen::MatrixXd normals() const;
  /// One surface of every part (faces renumbered), for the cage.
  io::SurfaceMesh joined() const;
};

/// Reads each file (a surface by extension, or a point list). Throws naming the file: no points,
/// or a column count that differs from the first part's.
DenseParts read_dense_parts(const std::vector<std::string>& files);

}  // namespace mbi::cli
