// The page's scenes (scene_files.hpp): a scene file's models and simulation as `mbi run` builds
// them (mbi::scene_format), and a user's surface as `mbi view MODEL` runs it.
#include <mbi/web/page_model.hpp>
#include <mbi/web/scene_files.hpp>

#include <mbi/interp/embed.hpp>
#include <mbi/scenes/model_scene.hpp>
#include <mbi/scenes/models.hpp>

#include <string>
#include <utility>

namespace mbi::web {
namespace {

std::string counts(const scenes::SceneModels& m) {
  return std::to_string(m.dense.V.rows()) + " dense vertices, " + std::to_string(m.U.rows()) + " control vertices";
}

}  // namespace

scenes::Scene parse(const SceneFile& file) {
  return scenes::parse_scene(file.text, "scenes/" + std::string(file.name) + ".toml");
}

std::string page_problem(const scenes::Scene& s) {
  if (!s.dense.path.empty() || !s.more_dense.empty() || !s.dense.image.empty() || !s.control.path.empty())
    return "it reads model files, and the page has no file system";
  if (s.dense.builtin == scenes::DenseBuiltin::ImageGrid || s.control.builtin == scenes::ControlBuiltin::Grid2D)
    return "it is 2D (a picture warped in its plane), and the page draws surfaces in 3D";
  if (s.mode != scenes::Mode::Simulate)
    return "its handles are dragged by keyframes, and the page's pokes pull on a simulation";
  for (std::size_t k = 0; k < s.colliders.size(); ++k)
    if (s.colliders[k].shape == pipeline::ColliderShape::Mesh)
      return "colliders[" + std::to_string(k) + "].shape = \"mesh\": a mesh collider's distances are an OpenVDB level "
             "set, and the page's build has no OpenVDB (planes, spheres, boxes and capsules run here)";
  return "";
}

PageModel PageModel::scene(const scenes::Scene& scene) {
  if (const std::string why = page_problem(scene); !why.empty())
    throw scenes::Error(scene.file.string() + ": the page cannot run this scene: " + why);
  scenes::Scene s = scene;
  if (s.interpolation.method != pipeline::Method::BI) s.interpolation.method = pipeline::Method::ModifiedBI;
  scenes::SceneModels m = scenes::load_models(s);
  pipeline::FramePipeline pipe = scenes::make_pipeline(s, m, interp::embed(m.U, m.T, m.dense.V));
  std::string what = s.name + ": " + m.dense_name + ", " + counts(m);
  return PageModel(Surface{std::move(m.dense.V), std::move(m.dense.F)}, std::move(pipe), std::move(what));
}

PageModel PageModel::surface(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int control_vertices) {
  scenes::Scene s = scenes::surface_scene("model.obj");
  s.control.generate_vertices = control_vertices;
  io::SurfaceMesh dense;
  dense.V = V;
  dense.F = F;
  // a flat model gets a 3D cage too: the simulator is 3D
  scenes::SceneModels m = scenes::load_models(s, std::move(dense), "your model", true);
  scenes::fit_to_model(s, m.dense.V);
  pipeline::FramePipeline pipe = scenes::make_pipeline(s, m, interp::embed(m.U, m.T, m.dense.V));
  std::string what = "your model: " + counts(m);
  return PageModel(Surface{std::move(m.dense.V), std::move(m.dense.F)}, std::move(pipe), std::move(what));
}

}  // namespace mbi::web
