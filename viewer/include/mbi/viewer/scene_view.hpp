#pragma once
// `mbi view SCENE` / `mbi view MODEL`: a scene's models and frame pipeline in the viewer (the
// scene's simulation or drags; Young's modulus and Poisson ratio editable: the simulation is
// rebuilt), or a bare model in the scene made for it (mbi/scenes/model_scene.hpp). A model file
// dropped on the window replaces what is shown; one that cannot be loaded is said (panel,
// stderr) and the session goes on.
#include <mbi/scenes/runner.hpp>
#include <mbi/viewer/viewer.hpp>

namespace mbi::viewer {

/// Opens the viewer on a scene (mesh_override replaces its dense model) until it closes. The
/// scene's files (scene, models, image, control mesh) are inputs of the session: never outputs;
/// the options' files are checked before the models are loaded. Throws Error (no display,
/// a write error), mbi::Error (bad scene, models or files).
void view_scene(const scenes::Scene& scene, const std::filesystem::path& mesh_override, ViewerOptions options);

/// Opens the viewer on a bare model: a surface file (every format io::read_surface reads) or a
/// built-in model's name (scenes::builtin_model); paused, pokes on. Throws as view_scene.
void view_model(const std::filesystem::path& model, ViewerOptions options);

}  // namespace mbi::viewer
