// load_scene: a scene file read from disk, with the meshes its colliders name (scene.hpp).
// Apart from scene.cpp, which parses text alone (the fuzz target compiles it without mbi::io's
// readers or OpenVDB).
#include "model_files.hpp"

#include <mbi/io/parse.hpp>

#include <string>

namespace mbi::scenes {
namespace {

// The key of a MeshLevelSet message: its voxel size, or else the mesh itself (its file).
bool about_voxel_size(const std::string& what) { return what.find("voxel_size") != std::string::npos; }

}  // namespace

Scene load_scene(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw Error(file.string() + ": no such scene file");
  std::string text;
  try {
    text = io::read_bytes(file);  // regular files only: a FIFO or a device is refused, not read
  } catch (const io::Error& e) {
    throw Error(e.what());
  }
  Scene sc = parse_scene(text, file);
  read_collider_meshes(sc);
  return sc;
}

std::shared_ptr<const pipeline::MeshLevelSet> read_collider_mesh(const Scene& sc, const ColliderMesh& mesh) {
  const std::string key = "colliders[" + std::to_string(mesh.index) + "].";
  const std::filesystem::path file = resolve_path(sc, mesh.path);
  io::SurfaceMesh surface;
  try {
    surface = read_surface(sc, file, (key + "path").c_str());
  } catch (const Error&) {
    throw;  // a build without model files: the refusal names the scene and the key
  } catch (const mbi::Error& e) {
    throw Error(mesh.where_path + ": " + key + "path: " + e.what());
  }
  try {
    return std::make_shared<const pipeline::MeshLevelSet>(surface.V, surface.F, mesh.options);
  } catch (const mbi::Error& e) {
    const std::string what = e.what();
    if (about_voxel_size(what)) throw Error(mesh.where_voxel_size + ": " + key + "voxel_size: " + what);
    throw Error(mesh.where_path + ": " + key + "path: " + file.string() + ": " + what);
  }
}

void read_collider_meshes(Scene& sc) {
  for (const ColliderMesh& mesh : sc.collider_meshes) {
    pipeline::Collider& c = sc.colliders.at(mesh.index);
    if (!c.level_set) c.level_set = read_collider_mesh(sc, mesh);
  }
}

}  // namespace mbi::scenes
