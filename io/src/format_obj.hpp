#pragma once
// Wavefront OBJ surfaces (format_obj.cpp).
#include <mbi/io/io.hpp>

#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace mbi::io::detail {

struct SurfaceOutput;

/// What an OBJ file holds besides positions, faces and normals (comments are not kept).
struct ObjAttributes {
  /// One record of the file: verbatim text, or the vertex / face of that index (written from
  /// the mesh). `vn` lines are not kept (N replaces them).
  struct Record {
    enum class Kind { text, vertex, face } kind;
    int index;
    std::string text;
  };
  std::vector<Record> records;                // in file order, comments and blank lines dropped
  std::vector<std::string> vertex_tail;       // per vertex: numbers after x y z, or empty
  std::vector<std::vector<int>> face_vt;      // per face and corner: 0-based vt, -1 = none
  std::filesystem::path file;                 // the file read (its mtllib names are relative to it)
};

/// read_surface of an OBJ file's bytes.
SurfaceMesh parse_obj(std::string_view data, const std::filesystem::path& file);
/// Whether attributes read from an OBJ file fit these faces (as many, each of the same size).
bool obj_attributes_fit(const SurfaceAttributes& a, const std::vector<std::vector<int>>& faces);
/// The OBJ file of `out` (always ASCII).
void write_obj(std::FILE* f, const SurfaceOutput& out);

}  // namespace mbi::io::detail
