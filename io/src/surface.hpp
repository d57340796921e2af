#pragma once
// What the surface formats (format_obj/off/ply/stl.cpp) share: the attributes a surface file
// keeps, what a surface writer is given, and the steps that make a SurfaceMesh.
#include "format_obj.hpp"
#include "format_off.hpp"
#include "format_ply.hpp"
#include "format_stl.hpp"
#include "io_common.hpp"

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace mbi::io {
namespace detail {
struct GltfAsset;
}

/// Everything a surface file holds besides positions, faces and normals (see SurfaceMesh).
struct SurfaceAttributes {
  std::string format;       // ".obj", ".ply", ".stl" or ".glb"
  bool binary = false;      // PLY, STL
  bool big_endian = false;  // binary PLY
  long long vertices = 0;   // vertex count of the file (attributes fit a mesh with as many)
  detail::ObjAttributes obj;
  detail::PlyAttributes ply;
  detail::StlAttributes stl;
  std::shared_ptr<const detail::GltfAsset> gltf;  // .gltf and .glb (format ".glb")
};

namespace detail {

/// Faces as written: 0-based vertex indices, any size >= 3.
using Polygons = std::vector<std::vector<int>>;

/// What a surface writer writes, checked by the caller (write_surface_positions).
struct SurfaceOutput {
  const std::filesystem::path& file;
  const Eigen::Ref<const Eigen::MatrixXd>& V;  ///< n x 3, finite
  const Eigen::Ref<const Eigen::MatrixXd>& N;  ///< n x 3 unit normals, or empty: none
  const Polygons& faces;                       ///< indices in [0, n); triangles for STL
  /// The attributes of a file of this format that fit V and faces (to write back), or null.
  const SurfaceAttributes* attributes;
  bool binary;      ///< binary encoding (the formats that have one)
  bool big_endian;  ///< binary PLY only
  bool has_normals() const { return N.size() > 0; }
};

/// write_surface with the faces and attributes of `mesh`, and the positions V (n x 3) and
/// normals N (n x 3 or empty) in place of mesh.V and mesh.N (no copy of the mesh per frame).
void write_surface_positions(const std::filesystem::path& file, const SurfaceMesh& mesh,
                             const Eigen::Ref<const Eigen::MatrixXd>& V,
                             const Eigen::Ref<const Eigen::MatrixXd>& N, Encoding encoding);

/// The faces a writer writes: mesh.polygons, or the triangles F when there are no polygons or
/// `triangles` is set; checks V (n x 3, finite) and every index against it.
Polygons faces_of(const SurfaceMesh& mesh, const Eigen::Ref<const Eigen::MatrixXd>& V,
                  const std::filesystem::path& file, bool triangles);

/// m.V from the positions read.
void set_vertices(SurfaceMesh& m, const std::vector<std::array<double, 3>>& v);
/// m.F from m.polygons, each fan-triangulated (v0, vk, vk+1).
void fan(SurfaceMesh& m);
/// Area-weighted vertex normals of the triangles F (as io::vertex_normals), written into the rows
/// of N where `have` is false; every row of N is then made unit length.
void complete_normals(SurfaceMesh& m, const std::vector<char>& have);
/// The same on V, F and N (V.rows() x 3); `have` may be empty (every row computed).
void complete_normals(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F,
                      Eigen::MatrixXd& N, const std::vector<char>& have);

/// The ASCII lines OFF and PLY share: "x y z" per vertex (then "nx ny nz" when
/// `with_normals`), and "k i0 .. ik-1" per face.
void put_vertex_lines(std::FILE* f, const SurfaceOutput& out, bool with_normals);
void put_counted_faces(std::FILE* f, const SurfaceOutput& out);

}  // namespace detail
}  // namespace mbi::io
