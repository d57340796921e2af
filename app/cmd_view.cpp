// mbi view SCENE|MODEL [--mesh FILE] [--method M] [--script FILE] [--record FILE] [--frames N]
//               [--screenshot PATH] [--report FILE] [--force] [--width W] [--height H]
//               [--paused] [--no-split] [--wireframe] [--creases] [--no-panel] [--gpu auto|on|off]
//               [--looks auto|full|software|plain] [--video FILE.mp4]
#include "commands.hpp"
#include "signals.hpp"

#include <mbi/io/io.hpp>
#include <mbi/pipeline/method.hpp>
#include <mbi/scenes/model_scene.hpp>
#include <mbi/viewer/scene_view.hpp>

#include <cstdio>
#include <optional>
#include <stdexcept>

namespace mbi::cli {
namespace {

struct ViewArgs {
  std::string scene, mesh, method, script, record, screenshot, report, video;
  viewer::Looks looks = viewer::Looks::Auto;
  int frames = 0, width = 1280, height = 720;
  std::optional<scenes::GpuUse> gpu;
  bool paused = false, no_split = false, wireframe = false, creases = false, no_panel = false, force = false;
};

viewer::ViewerOptions options_of(const ViewArgs& a) {
  viewer::ViewerOptions o;
  o.width = a.width;
  o.height = a.height;
  o.frames = a.frames;
  o.screenshot = a.screenshot;
  o.script = a.script;
  o.record = a.record;
  o.report = a.report;
  o.video = a.video;
  o.looks = a.looks;
  o.playing = !a.paused;
  o.split = !a.no_split;
  o.wireframe = a.wireframe;
  o.creases = a.creases;
  o.panel = !a.no_panel;
  o.force = a.force;
  return o;
}

// A bare model: paused, pokes on, the scene made for it; a .toml: a scene.
int run_view(const ViewArgs& a) {
  viewer::ViewerOptions o = options_of(a);
  handle_interrupts(nullptr);  // Ctrl-C ends the session at once, leaving no reserved temporaries
  if (scenes::is_model(a.scene)) {
    if (!a.mesh.empty()) throw std::runtime_error("--mesh replaces a scene's model: give " + a.mesh + " alone");
    if (!a.method.empty()) throw std::runtime_error("--method applies to a scene: the model is shown in modified-bi");
    o.playing = false;
    if (a.gpu) o.gpu = *a.gpu;
    viewer::view_model(a.scene, o);
    return 0;
  }
  if (io::lower_extension(a.scene) != ".toml")
    throw std::runtime_error(a.scene + ": neither a scene (.toml) nor a model (" +
                             io::extensions_of(io::FileKind::surface) + ", or a built-in: cylinder, bumpy-sphere, paper-bar)");
  scenes::Scene sc = scenes::load_scene(a.scene);
  if (!a.method.empty()) sc.interpolation.method = *pipeline::parse_method(a.method);
  if (a.gpu) sc.interpolation.gpu = *a.gpu;
  viewer::view_scene(sc, a.mesh, o);
  return 0;
}

const Registrar reg{
    "view", "Open a scene or a model in the interactive viewer (pokes, direct dragging, split view, video)",
    [](CLI::App& sub) -> Action {
      auto a = std::make_shared<ViewArgs>();
      sub.add_option("scene", a->scene,
                     "scene file (.toml), or a model (a surface file, or cylinder, bumpy-sphere, paper-bar): "
                     "shown paused in a generated control mesh, pokes on")
          ->required();
      sub.add_option("--mesh", a->mesh, "dense model replacing the scene's (.obj/.ply/.off/.stl)");
      sub.add_option("--method", a->method, "interpolation replacing the scene's")
          ->check(CLI::IsMember(pipeline::kMethodNames.names()));
      sub.add_option("--script", a->script, "replay recorded input events (FRAME EVENT ARGS per line)");
      sub.add_option("--record", a->record, "record the input events to this file");
      sub.add_option("--frames", a->frames, "close after N frames (0 = when the window closes)")
          ->check(CLI::Range(0, 100000000));
      sub.add_option("--screenshot", a->screenshot, "write the last frame as PNG when closing");
      sub.add_option("--report", a->report, "write per-frame state (pokes, handles, energies) as JSON");
      sub.add_flag("--force", a->force,
                   "overwrite existing outputs (--record, --screenshot, --report, --video, p screenshots, o videos); inputs never");
      sub.add_option("--width", a->width, "window width")->check(CLI::Range(160, 8192));
      sub.add_option("--height", a->height, "window height")->check(CLI::Range(120, 8192));
      sub.add_flag("--paused", a->paused, "start paused");
      sub.add_flag("--no-split", a->no_split, "only the scene's method (no BI panel)");
      sub.add_flag("--wireframe", a->wireframe, "show the control mesh's edges");
      sub.add_flag("--creases", a->creases,
                   "colour the surface by the jump of the deformation gradient at the control faces (g key)");
      add_choice(sub, "--gpu", a->gpu, scenes::kGpuUseNames,
                 "evaluator: auto (the CPU kernel on a software OpenGL renderer such as llvmpipe, else "
                 "the GPU), on (the GPU), off (the CPU); default: the scene's interpolation.gpu, auto");
      sub.add_flag("--no-panel", a->no_panel, "hide the control panel (clean screenshots)");
      add_choice(sub, "--looks", a->looks, viewer::kLooksNames,
                 "full (ground, grid, soft shadow, clay material, MSAA), software (the same without MSAA), "
                 "plain (white, headlight); auto: software on a software OpenGL renderer (llvmpipe), else full");
      sub.add_option("--video", a->video,
                     "record the window from the first frame to FILE (.mp4, .mkv, .mov, .webm; 30 fps) through "
                     "ffmpeg; the o key pauses it (without --video, o starts and stops mbi-video-FRAME.mp4)");
      add_threads_option(sub);
      return [a] { return run_view(*a); };
    }};

}  // namespace
}  // namespace mbi::cli
