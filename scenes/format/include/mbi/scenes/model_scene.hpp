#pragma once
// A scene for a bare model (`mbi view MODEL`, a file dropped on the viewer): the model in a
// generated control mesh, simulated, held at its bottom, no scripted pokes (the user pokes).
//
// The material is scaled to the model's size so that every model, 15 cm or 6 m, wobbles alike:
// Young's modulus E = rho (L / 1.3 s)^2 with L the bounding-box diagonal (m) and rho = 1000
// kg/m^3, so a wave crosses the model in about 1.3 s; the time step then stays one frame (1/30 s,
// 2 substeps), stable and visibly smooth at any size.
#include <mbi/scenes/scene.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <optional>

namespace mbi::scenes {

/// The built-in 3D model named `arg` ("cylinder", "bumpy-sphere", "paper-bar"), if it names
/// one and is not an existing file.
std::optional<DenseBuiltin> builtin_model(const std::filesystem::path& arg);

/// Whether `arg` is a bare model rather than a scene: a surface file by its extension
/// (io::is_surface_file, every format mbi reads) or a built-in model's name.
bool is_model(const std::filesystem::path& arg);

/// The scene of a bare model before its size is known: the dense model (file or built-in), a
/// control mesh of about 150 vertices generated around it, modified BI, y up.
Scene model_scene(const std::filesystem::path& model);
/// model_scene without a dense model, for one given in memory (the page reads an OBJ's text):
/// load_models(scene, surface, name) adds it. `name` names the scene in messages.
Scene surface_scene(const std::filesystem::path& name);

/// Fits the scene to the model's rest positions V (n x 3): the material scaled to its size (see
/// above), the bottom tenth held (along y; along the longest axis for a model flat in y).
void fit_to_model(Scene& scene, const Eigen::Ref<const Eigen::MatrixXd>& V);

}  // namespace mbi::scenes
