#pragma once
// PLY surfaces, ASCII and binary of either endianness (format_ply.cpp).
#include <mbi/io/io.hpp>

#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace mbi::io::detail {

struct SurfaceOutput;

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

struct PlyProp {
  std::string name;
  std::string type_name, count_type_name;  // as written in the header
  PlyType type = PlyType::f32;
  bool list = false;
  PlyType count_type = PlyType::u8;
  int line = 0;  // in the header
};

struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProp> props;
  int line = 0;
};

/// What a PLY file holds besides positions, faces and normals: all of it.
struct PlyAttributes {
  std::vector<std::string> comments;        // header comment / obj_info lines
  std::vector<PlyElement> elements;         // as declared
  /// Every value of every element: per element, record after record; a list is its count,
  /// then its items.
  std::vector<std::vector<double>> values;
  std::vector<int> face_sizes;              // sizes of the face element's vertex lists
};

/// read_surface of a PLY file's bytes.
SurfaceMesh parse_ply(std::string_view data, const std::filesystem::path& file);
/// Whether attributes read from a PLY file fit these faces (as many, each of the same size).
bool ply_attributes_fit(const SurfaceAttributes& a, const std::vector<std::vector<int>>& faces);
/// The PLY file of `out`: its attributes with the positions, normals and faces replaced, or
/// float64 coordinates and normals and int32 indices when it has none.
void write_ply(std::FILE* f, const SurfaceOutput& out);

}  // namespace mbi::io::detail
