#pragma once
// A scene's models and what moves them: the dense model and the control mesh (read, built in or
// generated), the driver (the simulation with its constraints and scripted pokes, or the dragged
// handles) and the frame pipeline around them. Everything that runs a scene (the runner, the
// viewer, the page, benchmarks) builds them here.
#include <mbi/interp/embed.hpp>
#include <mbi/io/image.hpp>
#include <mbi/io/io.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/scenes/scene.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mbi::scenes {

/// A scene's models, ready to run: the dense model and the control mesh in one dimension d.
/// One of several dense models ([[dense]]): its rows in SceneModels::dense and its own surface
/// (attributes, for its own output files).
struct DensePart {
  std::string name;
  Eigen::Index first = 0, rows = 0;
  io::SurfaceMesh surface;
};

struct SceneModels {
  io::SurfaceMesh dense;           ///< 3D: the surface; 2D: V n x 2 grid, F triangles
  /// Several dense models: every part, in order (dense is then all of them joined: faces
  /// renumbered, normals when every part has them, no attributes); empty for one model.
  std::vector<DensePart> dense_parts;
  Eigen::MatrixXd U;               ///< control rest positions n x d
  Eigen::MatrixXi T;               ///< control elements m x (d+1)
  std::optional<io::Image> image;  ///< 2D: the texture (pixels; dense V are pixel coordinates)
  std::string dense_name, control_name;
  double generate_seconds = 0;     ///< time spent generating the control mesh, s
  /// A flat 3-coordinate dense model run in 2D: its plane z (written back in every mesh).
  std::optional<double> flat_z;
  int dim() const { return static_cast<int>(U.cols()); }
};

/// Loads (or builds) the dense model and the control mesh of a scene. mesh_override replaces the
/// scene's dense model. Throws Error / io::Error naming the file. A build with MBI_IO_OBJ_ONLY
/// (the page, no file system) reads no model files: a scene that names one throws Error naming
/// the key (dense.path, dense.image, control.path).
///
/// 2D as everywhere in mbi: a dense model with 3 coordinates all at one z is flat, and runs in
/// 2D (z dropped, kept in flat_z) unless `force_3d`, or unless the control mesh is read from a
/// 3D file (its dimension decides, as in mbi deform).
SceneModels load_models(const Scene& scene, const std::filesystem::path& mesh_override = {},
                        bool force_3d = false);
/// load_models with the dense model given instead of read (as `mesh_override` replaces the
/// scene's; the page reads an OBJ's text itself); `name` names it in messages.
SceneModels load_models(const Scene& scene, io::SurfaceMesh dense, const std::string& name,
                        bool force_3d = false);

/// The frame pipeline of a scene: a SimulatorDriver (material, time stepping, constraints,
/// scripted pokes) in simulate mode, a HandleDriver following the [[drags]] keyframes in drag
/// mode; the scene's method, alpha and pin_boundary. evaluator: nullptr = CPU, double. Throws Error
/// (pokes outside the control mesh, drag vertices out of range or repeated, simulate in 2D).
pipeline::FramePipeline make_pipeline(const Scene& scene, const SceneModels& models,
                                      interp::Embedding embedding,
                                      std::unique_ptr<pipeline::Evaluator> evaluator = nullptr);

/// The driver alone of make_pipeline (to rebuild a simulation with another material).
std::unique_ptr<pipeline::Driver> make_driver(const Scene& scene, const SceneModels& models);

}  // namespace mbi::scenes
