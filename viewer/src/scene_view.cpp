#include <mbi/generate/procedural.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/scenes/model_scene.hpp>
#include <mbi/scenes/output_folder.hpp>
#include <mbi/viewer/scene_view.hpp>

#include "session_io.hpp"

#include <optional>

namespace mbi::viewer {
namespace {

// What one show() displays: a scene and its models.
struct Loaded {
  scenes::Scene scene;
  scenes::SceneModels models;
};

// A bare model in the scene made for it (generated control mesh, material fitted to its size);
// a flat model stays 3D (tetrahedra), so it can be poked like any other.
Loaded load_model(const std::filesystem::path& model) {
  Loaded l{scenes::model_scene(model), {}};
  l.models = scenes::load_models(l.scene, {}, true);
  scenes::fit_to_model(l.scene, l.models.dense.V);
  return l;
}

// Shows `l` until the window closes, the frames pass, or a model is dropped.
void show(Viewer& viewer, const Loaded& l) {
  const scenes::Scene& scene = l.scene;
  const scenes::SceneModels& models = l.models;
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

// The session: the first scene, then each model dropped on the window; one that cannot be
// loaded is said, and the current one stays.
void run(ViewerOptions options, std::unique_ptr<SessionFiles> files, Loaded first) {
  options.accept_drops = true;
  Viewer viewer(options, std::move(files));
  Loaded current = std::move(first);
  while (true) {
    show(viewer, current);
    const std::filesystem::path dropped = viewer.dropped();
    if (dropped.empty()) return;
    try {
      if (!scenes::is_model(dropped))
        throw Error("not a model (" + io::extensions_of(io::FileKind::surface) + ")");
      current = load_model(dropped);
      viewer.options().up = current.scene.output.up;
    } catch (const std::exception& e) {
      viewer.say(dropped.string() + ": " + e.what());
    }
  }
}

}  // namespace

void view_scene(const scenes::Scene& scene_in, const std::filesystem::path& mesh_override, ViewerOptions options) {
  Loaded first{scene_in, {}};
  for (const std::filesystem::path& p : scenes::input_files(first.scene, mesh_override)) options.inputs.push_back(p);
  options.up = first.scene.output.up;
  options.gpu = first.scene.interpolation.gpu;
  if (options.title == "mbi") options.title = "mbi view: " + first.scene.name;
  // the files before any work, the models before the window
  auto files = std::make_unique<SessionFiles>(options);
  first.models = scenes::load_models(first.scene, mesh_override);
  run(options, std::move(files), std::move(first));
}

void view_model(const std::filesystem::path& model, ViewerOptions options) {
  if (!scenes::builtin_model(model)) options.inputs.push_back(model);
  if (options.title == "mbi") options.title = "mbi view: " + model.filename().string();
  auto files = std::make_unique<SessionFiles>(options);
  Loaded first = load_model(model);
  options.up = first.scene.output.up;
  run(options, std::move(files), std::move(first));
}

}  // namespace mbi::viewer
