#pragma once
// STL surfaces, ASCII and binary (format_stl.cpp).
#include <mbi/io/io.hpp>

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace mbi::io::detail {

struct SurfaceOutput;

/// What an STL file holds besides its triangles.
struct StlAttributes {
  std::string header;                 // binary: the 80-byte header; ASCII: the solid's name
  std::vector<std::uint16_t> words;   // binary: per triangle, its attribute word (empty: all 0)
  long long triangles = 0;
};

/// read_surface of an STL file's bytes: the corners of its triangles merged when bitwise equal,
/// in order of first appearance.
SurfaceMesh parse_stl(std::string_view data, const std::filesystem::path& file);
/// Whether attributes read from an STL file fit these triangles (as many).
bool stl_attributes_fit(const SurfaceAttributes& a, const std::vector<std::vector<int>>& faces);
/// The STL file of `out` (triangles; facet normals from the positions).
void write_stl(std::FILE* f, const SurfaceOutput& out);

}  // namespace mbi::io::detail
