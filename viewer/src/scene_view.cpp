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
  shown.material = {.youngs_modulus = scene.material.young, .poisson_ratio = scene.material.poisson,
                    .density = scene.material.density};
  if (scene.mode == scenes::Mode::Simulate)
    shown.rebuild = [&](const sim::Material& m) {
      scenes::Scene changed = scene;
      changed.material.young = m.youngs_modulus;
      changed.material.poisson = m.poisson_ratio;
      return scenes::make_driver(changed, models);
    };
  viewer.show(shown);
}

}  // namespace mbi::viewer
