#pragma once
// mbi::viewer -- the interactive viewer (`mbi view SCENE`): a GLFW window with OpenGL core, a
// Dear ImGui panel docked at the left, the views labelled with their method beside it (layout.hpp),
// the dense mesh drawn from GL buffers that the GPU pass or the CPU kernel fills (options.gpu),
// driven by one frame pipeline. Pokes (grab the surface, a bounded spring pulls it), direct mode (click control
// vertices to make them handles and drag them: paper Eq. 10/11), BI | modified-BI split view.
//
// A few lines open a viewer on any pipeline (in the spirit of polyscope):
//
//   mbi::viewer::Viewer viewer;                        // window + OpenGL context
//   mbi::pipeline::FramePipeline pipe(U, T, mbi::interp::embed(U, T, P), std::move(driver),
//                                     {.normals = true}, viewer.evaluator(), rest_normals);
//   viewer.show({.pipe = pipe, .faces = F,
//                .per_frame = [&](mbi::viewer::Viewer&) { given.set(next_positions()); }});
//
// Input replay: `script` lines "FRAME EVENT ARGS" (mbi/viewer/script.hpp); `record` writes the
// same lines for what the user did, so a session can be replayed.
//
// Files: the options' outputs (record, screenshot, report) follow the rules of every mbi command
// (docs/hardening.md): checked and reserved when the Viewer is made, before any work; never one
// of `inputs` or the script, never two at one file, only regular files (a FIFO or a device is
// refused), an existing file only with `force`; all moved into place when show() returns, none
// on an error. A write error is an error.
#include <mbi/base/names.hpp>
#include <mbi/gpu/evaluator.hpp>
#include <mbi/io/image.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/scenes/scene.hpp>
#include <mbi/sim/corotational.hpp>
#include <mbi/viewer/error.hpp>

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mbi::viewer {

/// How the 3D views look. Full: a ground with a grid and a soft shadow, the clay material,
/// anti-aliasing (4x MSAA); Software: the same without MSAA, for a software renderer's frame
/// rate; Plain: a white background and a headlight only; Auto: Software on a software OpenGL
/// renderer (llvmpipe, softpipe), else Full.
enum class Looks { Auto, Full, Software, Plain };
inline constexpr auto kLooksNames = name_table<Looks>(
    {{Looks::Auto, "auto"}, {Looks::Full, "full"}, {Looks::Software, "software"}, {Looks::Plain, "plain"}});

struct ViewerOptions {
  int width = 1280, height = 720;        ///< window size (logical pixels)
  std::string title = "mbi";
  bool split = true;                     ///< BI | the pipeline's method side by side
  bool wireframe = false;                ///< control-mesh edges
  /// 3D: the dense surface coloured by the jump of the deformation gradient across the interior
  /// control faces (mbi/pipeline/creases.hpp), one scale for all views, with a legend
  bool creases = false;
  bool handles = true;                   ///< handle markers (direct mode)
  bool playing = true;
  bool panel = true;                     ///< the ImGui panel
  /// Evaluator: Auto picks the CPU kernel on a software OpenGL renderer, else the GPU pass.
  scenes::GpuUse gpu = scenes::GpuUse::Auto;
  int frames = 0;                        ///< > 0: close after this many frames
  std::filesystem::path screenshot;      ///< written when the viewer closes (PNG)
  std::filesystem::path script;          ///< input events to replay
  std::filesystem::path record;          ///< input events to record
  std::filesystem::path report;          ///< JSON per frame: pokes, handles, energies (tests)
  std::filesystem::path video;           ///< recorded from the first frame (ffmpeg; video.hpp)
  Looks looks = Looks::Auto;
  /// A model file dropped on the window ends show() (Viewer::dropped); view_scene loads it.
  /// Off: a drop is only said (a caller's own show() runs on).
  bool accept_drops = false;
  std::vector<std::filesystem::path> inputs;  ///< the files shown (scene, models): never outputs
  bool force = false;                    ///< replace existing output files (never an input)
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  double poke_response = 0.15;           ///< s, natural period of a poke spring
};

class Viewer;
class SessionFiles;

/// What Viewer::show displays: a frame pipeline and the surface it deforms; in 2D the picture
/// drawn on it; the simulation's material, editable in the panel when `rebuild` is given.
struct Shown {
  pipeline::FramePipeline& pipe;      ///< built with Viewer::evaluator()
  const Eigen::MatrixXi& faces;       ///< t x 3: 3D the dense surface; 2D the triangles drawn textured
  const io::Image* image = nullptr;   ///< 2D: the picture (required); 3D: unused
  std::function<void(Viewer&)> per_frame = {};  ///< runs before each step; may be empty
  sim::Material material = {};        ///< Young's modulus (Pa) and Poisson ratio shown in the panel
  /// A new simulation driver for an edited material (the simulation restarts); empty: the
  /// material is not editable.
  std::function<std::unique_ptr<pipeline::Driver>(const sim::Material&)> rebuild = {};
};

class Viewer {
 public:
  /// Checks the options' files (mbi::Error naming the option), then opens the window and its
  /// OpenGL context. Throws Error (no display: one line).
  explicit Viewer(const ViewerOptions& options = {});
  /// With the session's files checked already (internal: view_scene checks them before it
  /// loads the models, then opens the window).
  Viewer(const ViewerOptions& options, std::unique_ptr<SessionFiles> files);
  ~Viewer();
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  /// The evaluator options.gpu asks for, for the pipeline to show: the GPU pass in the viewer's
  /// context, or the CPU kernel uploading its results into the buffers the renderer draws.
  std::unique_ptr<pipeline::Evaluator> evaluator();

  /// Shows `shown` until the window closes or options.frames pass, then writes the files the
  /// options ask for (the first show() only). Throws Error (a pipeline not built with
  /// Viewer::evaluator(), 2D without an image, a write error), io::Error.
  void show(const Shown& shown);

  /// The last frame's picture of the window (RGB), kept while Shown::per_frame is set or
  /// options.screenshot asks for one (otherwise the last one kept, or an empty image).
  io::Image screenshot();
  int frame() const;
  /// A model file dropped on the window (or a script's drop event): show() then returns at
  /// once, before the frame's drawing, without writing the files; the caller loads the model
  /// and calls show() again (view_scene does). Empty when show() returned for another reason.
  std::filesystem::path dropped() const;
  /// A line for the user: the panel and stderr (a dropped file that cannot be loaded).
  void say(const std::string& message);
  ViewerOptions& options();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mbi::viewer
