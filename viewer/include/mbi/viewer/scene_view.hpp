#pragma once
// `mbi view SCENE`: a scene's models and frame pipeline in the viewer (the scene's simulation or
// drags; Young's modulus and Poisson ratio editable: the simulation is rebuilt).
#include <mbi/scenes/runner.hpp>
#include <mbi/viewer/viewer.hpp>

namespace mbi::viewer {

/// Opens the viewer on a scene (mesh_override replaces its dense model) until it closes. The
/// scene's files (scene, models, image, control mesh) are inputs of the session: never outputs;
/// the options' files are checked before the models are loaded. Throws ViewerError (no display,
/// a write error), mbi::Error (bad scene, models or files).
void view_scene(const scenes::Scene& scene, const std::filesystem::path& mesh_override, ViewerOptions options);

}  // namespace mbi::viewer
