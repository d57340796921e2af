#pragma once
// OFF surfaces, ASCII (format_off.cpp). No attributes: positions and faces only.
#include <mbi/io/io.hpp>

#include <cstdio>
#include <string_view>

namespace mbi::io::detail {

struct SurfaceOutput;

/// read_surface of an OFF file's bytes.
SurfaceMesh parse_off(std::string_view data, const std::filesystem::path& file);
/// The OFF file of `out` (always ASCII; normals are not written).
void write_off(std::FILE* f, const SurfaceOutput& out);

}  // namespace mbi::io::detail
