#pragma once
// The scene files the page offers: scenes/*.toml of the source tree, embedded at build time
// (web/CMakeLists.txt generates their source; the page has no file system), so that a new scene
// file reaches the page without C++. Which of them the page can run: page_problem().
#include <mbi/scenes/scene.hpp>

#include <span>
#include <string>
#include <string_view>

namespace mbi::web {

struct SceneFile {
  std::string_view name;  ///< the file's stem, e.g. "twist-bar"
  std::string_view text;  ///< its TOML
};

/// The embedded scene files, by name.
std::span<const SceneFile> scene_files();

/// A scene file's scene (scenes::parse_scene; messages name scenes/<name>.toml). Throws
/// scenes::Error.
scenes::Scene parse(const SceneFile& file);

/// Why the page cannot run `scene`, "" when it can: it names a model file (the page has no file
/// system), it is 2D (the page draws surfaces in 3D), its handles are dragged by keyframes
/// (the page's pokes pull on a simulation) or it has a mesh collider (no OpenVDB in the page's
/// build), named by its key.
std::string page_problem(const scenes::Scene& scene);

}  // namespace mbi::web
