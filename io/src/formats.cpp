// The format table: every format mbi reads or writes, by extension, with the functions that
// read and write it. Every choice of a format by extension goes through here: the readers and
// writers of io.hpp, and the command line (file_format, read_positions, control_mesh_files).
#include "control.hpp"
#include "format_gltf.hpp"
#include "surface.hpp"

namespace mbi::io {
namespace {

using detail::fail;
using detail::Polygons;
using detail::SurfaceOutput;
using std::filesystem::path;

// One format: what a caller may know (FileFormat), and its functions, null where it has none.
struct FormatRow {
  FileFormat format;
  // surfaces
  SurfaceMesh (*parse_surface)(std::string_view data, const path& file) = nullptr;
  void (*write_surface)(std::FILE* f, const SurfaceOutput& out) = nullptr;
  // whether attributes read from a file of this format fit the faces to write (null: a file of
  // this format keeps none)
  bool (*attributes_fit)(const SurfaceAttributes& a, const Polygons& faces) = nullptr;
  bool triangles_only = false;  // writes the triangles F, never polygons
  // control meshes and positions
  ControlMesh (*read_control)(const path& file) = nullptr;
  Eigen::MatrixXd (*read_positions)(const path& file) = nullptr;
  std::vector<path> (*control_files)(const path& file) = nullptr;  // null: the file itself
};

constexpr FormatRow kFormats[] = {
    {.format = {".obj", "Wavefront OBJ", FileKind::surface},
     .parse_surface = detail::parse_obj,
     .write_surface = detail::write_obj,
     .attributes_fit = detail::obj_attributes_fit},
    {.format = {".off", "OFF", FileKind::surface},
     .parse_surface = detail::parse_off,
     .write_surface = detail::write_off},
    {.format = {".ply", "PLY", FileKind::surface},
     .parse_surface = detail::parse_ply,
     .write_surface = detail::write_ply,
     .attributes_fit = detail::ply_attributes_fit},
    {.format = {".stl", "STL", FileKind::surface},
     .parse_surface = detail::parse_stl,
     .write_surface = detail::write_stl,
     .attributes_fit = detail::stl_attributes_fit,
     .triangles_only = true},
    {.format = {".glb", "glTF 2.0 binary", FileKind::surface},
     .parse_surface = detail::parse_gltf,
     .write_surface = detail::write_gltf,
     .attributes_fit = detail::gltf_attributes_fit,
     .triangles_only = true},
    {.format = {".gltf", "glTF 2.0", FileKind::surface},
     .parse_surface = detail::parse_gltf,
     .write_surface = detail::write_gltf,
     .attributes_fit = detail::gltf_attributes_fit,
     .triangles_only = true},
    {.format = {".node", "TetGen nodes", FileKind::control},
     .read_control = read_tetgen,
     .read_positions = read_node,
     .control_files = detail::tetgen_files},
    {.format = {".ele", "TetGen elements", FileKind::control},
     .read_control = read_tetgen,
     .control_files = detail::tetgen_files},
    {.format = {".face", "TetGen boundary faces", FileKind::control},
     .read_control = read_tetgen,
     .control_files = detail::tetgen_files},
    {.format = {".msh", "Gmsh", FileKind::control},
     .read_control = read_gmsh,
     .read_positions = read_gmsh_nodes},
    {.format = {".vtk", "legacy VTK", FileKind::control},
     .read_control = read_vtk_mesh,
     .read_positions = read_vtk_points},
    {.format = {".vtu", "VTK XML unstructured grid", FileKind::control},
     .read_control = read_vtu_mesh,
     .read_positions = read_vtu_points},
    {.format = {".txt", "point list", FileKind::points}, .read_positions = read_points},
    {.format = {".xyz", "point list", FileKind::points}, .read_positions = read_points},
    {.format = {".pc2", "PC2 point cache", FileKind::cache}},
    {.format = {".mdd", "MDD point cache", FileKind::cache}},
    {.format = {".pvd", "ParaView collection", FileKind::collection}},
};
// A control mesh of any other name is a TetGen base name ("box", "box.1").
constexpr const FormatRow& kTetgen = kFormats[6];

const FormatRow* row_of(const path& file) {
  const std::string ext = lower_extension(file);
  for (const FormatRow& r : kFormats)
    if (ext == r.format.extension) return &r;
  return nullptr;
}

const FormatRow& surface_row(const path& file) {
  const FormatRow* r = row_of(file);
  if (!r || r->format.kind != FileKind::surface)
    fail(file, 0, "unknown surface format '" + lower_extension(file) + "' (expected " +
                      extensions_of(FileKind::surface) + ")");
  return *r;
}

const FormatRow& control_row(const path& file) {
  const FormatRow* r = row_of(file);
  return r && r->read_control ? *r : kTetgen;
}

// The mesh's attributes when they came from a file of this format and still fit (vertex count,
// faces), otherwise null.
const SurfaceAttributes* kept_attributes(const FormatRow& row, const SurfaceMesh& mesh,
                                         Eigen::Index vertices, const Polygons& faces) {
  const SurfaceAttributes* a = mesh.attributes.get();
  // .gltf and .glb hold the same document: attributes read from either fit both
  // and an OBJ's or PLY's convert to glTF (format_gltf_convert.cpp)
  const bool to_gltf = row.write_surface == detail::write_gltf && a && (a->gltf || a->format == ".obj" || a->format == ".ply");
  const bool same = a && (a->format == row.format.extension || to_gltf);
  const bool fit = same && row.attributes_fit &&
                   a->vertices == vertices && row.attributes_fit(*a, faces);
  return fit ? a : nullptr;
}

}  // namespace

const FileFormat* file_format(const path& file) {
  const FormatRow* r = row_of(file);
  return r ? &r->format : nullptr;
}

std::string extensions_of(FileKind kind) {
  std::vector<std::string> e;
  for (const FormatRow& r : kFormats)
    if (r.format.kind == kind) e.emplace_back(r.format.extension);
  std::string s;
  for (std::size_t i = 0; i < e.size(); ++i) s += (i == 0 ? "" : i + 1 == e.size() ? " or " : ", ") + e[i];
  return s;
}

bool is_surface_file(const path& file) {
  const FileFormat* f = file_format(file);
  return f && f->kind == FileKind::surface;
}

SurfaceMesh parse_surface(std::string_view data, const path& file) {
  return surface_row(file).parse_surface(data, file);
}

SurfaceMesh read_surface(const path& file) {
  std::error_code ec;  // what was given (a FIFO, a directory) is named before its extension
  if (std::filesystem::exists(file, ec)) detail::require_regular_file(file);
  const FormatRow& row = surface_row(file);
  return row.parse_surface(detail::slurp(file), file);
}

void write_surface(const path& file, const SurfaceMesh& mesh, Encoding encoding) {
  detail::write_surface_positions(file, mesh, mesh.V, mesh.N, encoding);
}

void write_surface(const path& file, const Eigen::Ref<const Eigen::MatrixXd>& V,
                   const Eigen::Ref<const Eigen::MatrixXi>& F, Encoding encoding) {
  SurfaceMesh m;
  m.V = V;
  m.F = F;
  write_surface(file, m, encoding);
}

void detail::write_surface_positions(const path& file, const SurfaceMesh& mesh,
                                     const Eigen::Ref<const Eigen::MatrixXd>& V,
                                     const Eigen::Ref<const Eigen::MatrixXd>& N,
                                     Encoding encoding) {
  const FormatRow& row = surface_row(file);
  if (V.cols() != 3) fail(file, 0, "positions must have 3 columns");
  const bool has_n = N.size() > 0;
  if (has_n && (N.rows() != V.rows() || N.cols() != 3))
    fail(file, 0, "normals must be " + std::to_string(V.rows()) + " x 3, got " +
                      std::to_string(N.rows()) + " x " + std::to_string(N.cols()));
  if (has_n) check_finite(N, file, "normal");
  const Polygons faces = faces_of(mesh, V, file, row.triangles_only);
  const SurfaceAttributes* attr = kept_attributes(row, mesh, V.rows(), faces);
  const bool binary =
      encoding == Encoding::binary || (encoding == Encoding::as_read && attr && attr->binary);
  const SurfaceOutput out{file, V, N, faces, attr, binary, binary && attr && attr->big_endian};
  write_atomic(file, [&](std::FILE* f) { row.write_surface(f, out); });
}

ControlMesh read_control_mesh(const path& file) { return control_row(file).read_control(file); }

std::vector<path> control_mesh_files(const path& file) {
  const FormatRow& row = control_row(file);
  return row.control_files ? row.control_files(file) : std::vector<path>{file};
}

Eigen::MatrixXd read_positions(const path& file) {
  const FormatRow* r = row_of(file);
  return (r && r->read_positions ? r->read_positions : read_points)(file);
}

}  // namespace mbi::io
