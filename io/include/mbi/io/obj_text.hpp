#pragma once
// An OBJ model from its text rather than a file (the browser page's dropped model).
#include <mbi/io/io.hpp>

#include <filesystem>
#include <string_view>

namespace mbi::io {

/// The text of an OBJ file, read as read_surface reads a .obj (`name` names it in messages).
/// Throws Error as read_surface does.
SurfaceMesh parse_obj_text(std::string_view text, const std::filesystem::path& name);

}  // namespace mbi::io
