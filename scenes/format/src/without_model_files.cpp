// A build that reads no model files (MBI_IO_OBJ_ONLY: the page, which has no file system): a
// scene that names one is refused, naming the key (model_files.hpp).
#include "model_files.hpp"

#include <mbi/scenes/model_scene.hpp>

#include <string>

namespace mbi::scenes {
namespace {

[[noreturn]] void refuse(const Scene& scene, const std::string& key, const std::filesystem::path& file) {
  throw Error(scene.file.string() + ": " + key + " names the file " + file.string() +
              ", but this build reads no model files (it has no file system); the scene runs in "
              "`mbi run` and `mbi view`");
}

}  // namespace

io::SurfaceMesh read_surface(const Scene& scene, const std::filesystem::path& file, const char* key) {
  refuse(scene, key, file);
}

io::ControlMesh read_control_mesh(const Scene& scene, const std::filesystem::path& file) {
  refuse(scene, "control.path", file);
}

io::Image read_image(const Scene& scene, const std::filesystem::path& file) { refuse(scene, "dense.image", file); }

bool is_model(const std::filesystem::path& arg) { return builtin_model(arg).has_value(); }

}  // namespace mbi::scenes
