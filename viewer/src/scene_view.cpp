#include <mbi/generate/procedural.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/scenes/output_folder.hpp>
#include <mbi/viewer/scene_view.hpp>

#include "session_io.hpp"

namespace mbi::viewer {

void view_scene(const scenes::Scene& scene_in, const std::filesystem::path& mesh_override, ViewerOptions options) {
  scenes::Scene scene = scene_in;
  for (const std::filesystem::path& p : scenes::input_files(scene, mesh_override)) options.inputs.push_back(p);
  options.up = scene.output.up;
  options.gpu = scene.interpolation.gpu;
  if (options.title == "mbi") options.title = "mbi view: " + scene.name;
  // the files before any work, the models before the window
  auto files = std::make_unique<SessionFiles>(options);
  const scenes::SceneModels models = scenes::load_models(scene, mesh_override);
  Viewer viewer(options, std::move(files));
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
