#include <mbi/generate/procedural.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/viewer/scene_view.hpp>

namespace mbi::viewer {

void view_scene(const scenes::Scene& scene_in, const std::filesystem::path& mesh_override, ViewerOptions options) {
  scenes::Scene scene = scene_in;
  const scenes::SceneModels models = scenes::load_models(scene, mesh_override);  // before the window
  options.up = scene.output.up;
  if (options.title == "mbi") options.title = "mbi view: " + scene.name;
  Viewer viewer(options);
  pipeline::FramePipeline pipe = scenes::make_pipeline(
      scene, models, interp::embed(models.U, models.T, models.dense.V), viewer.evaluator());
  const io::Image pattern = models.image ? *models.image : generate::test_pattern(512, 384);
  Shown shown{.pipe = pipe, .faces = models.dense.F, .image = models.dim() == 2 ? &pattern : nullptr};
  shown.material = scene.material;
  if (scene.mode == scenes::Mode::Simulate)
    shown.rebuild = [&](const sim::Material& m) {
      scenes::Scene changed = scene;
      changed.material.youngs_modulus = m.youngs_modulus;
      changed.material.poisson_ratio = m.poisson_ratio;
      return scenes::make_driver(changed, models);
    };
  viewer.show(shown);
}

}  // namespace mbi::viewer
