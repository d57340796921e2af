// The model files of a scene, read with mbi::io (model_files.hpp).
#include "model_files.hpp"

#include <mbi/scenes/model_scene.hpp>

namespace mbi::scenes {

io::SurfaceMesh read_surface(const Scene&, const std::filesystem::path& file, const char*) {
  return io::read_surface(file);
}

io::ControlMesh read_control_mesh(const Scene&, const std::filesystem::path& file) {
  return io::read_control_mesh(file);
}

io::Image read_image(const Scene&, const std::filesystem::path& file) { return io::read_png(file); }

bool is_model(const std::filesystem::path& arg) { return io::is_surface_file(arg) || builtin_model(arg); }

}  // namespace mbi::scenes
