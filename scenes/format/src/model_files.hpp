#pragma once
// The files a scene's models come from, read with mbi::io (model_files.cpp). A build with
// MBI_IO_OBJ_ONLY (the page: no file system) has without_model_files.cpp instead, which refuses
// them, naming the scene and the key.
#include <mbi/io/image.hpp>
#include <mbi/io/io.hpp>
#include <mbi/scenes/scene.hpp>

#include <filesystem>

namespace mbi::scenes {

/// The surface `file` that the scene's `key` names (dense.path, --mesh).
io::SurfaceMesh read_surface(const Scene& scene, const std::filesystem::path& file, const char* key);
/// The control mesh of control.path.
io::ControlMesh read_control_mesh(const Scene& scene, const std::filesystem::path& file);
/// The picture of dense.image.
io::Image read_image(const Scene& scene, const std::filesystem::path& file);

}  // namespace mbi::scenes
