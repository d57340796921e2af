#include <mbi/generate/procedural.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/viewer/scene_view.hpp>

namespace mbi::viewer {

int view_scene(const scenes::Scene& scene_in, const std::filesystem::path& mesh_override,
               ViewerOptions options) {
  scenes::Scene scene = scene_in;
  const scenes::SceneModels models = scenes::load_models(scene, mesh_override);  // before the window
  options.up = scene.output.up;
  if (options.title == "mbi") options.title = "mbi view: " + scene.name;
  Viewer viewer(options);
  pipeline::FramePipeline pipe = scenes::make_pipeline(
      scene, models, interp::embed(models.U, models.T, models.dense.V), viewer.evaluator());
  const io::Image pattern = models.image ? *models.image : generate::test_pattern(512, 384);
  auto rebuild = [&](double young, double poisson) {
    scenes::Scene changed = scene;
    changed.material.young = young;
    changed.material.poisson = poisson;
    return scenes::make_driver(changed, models);
  };
  return viewer.show(pipe, models.dense.F, {}, models.dim() == 2 ? &pattern : nullptr,
                     scene.mode == scenes::Mode::Simulate ? Viewer::Rebuild(rebuild) : Viewer::Rebuild(),
                     scene.material.young, scene.material.poisson);
}

}  // namespace mbi::viewer
