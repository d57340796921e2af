// run_scene: a scene's run from start to end, over its parts: the output folder
// (output_folder.cpp), the models and the pipeline (mbi/scenes/models.hpp), the evaluator
// (evaluator.cpp), the frames (frame_loop.cpp) and what they write (outputs.cpp, pictures.cpp,
// metrics.cpp).
#include "frame_loop.hpp"
#include "metrics.hpp"
#include "outputs.hpp"
#include "pictures.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/interp/mesh.hpp>
#include <mbi/scenes/evaluator.hpp>
#include <mbi/scenes/output_folder.hpp>
#include <mbi/scenes/runner.hpp>

#include <chrono>
#include <csignal>
#include <functional>
#include <optional>

namespace mbi::scenes {
namespace {

// The scene with the run's options in place of its own values.
Scene with_overrides(const Scene& scene, const RunOptions& opt) {
  // the scene file's own range for simulation.frames; 0 keeps the scene's
  if (opt.frames < 0 || opt.frames > 1000000)
    throw Error("frames = " + std::to_string(opt.frames) + ": give 1 to 1000000 frames, or 0 for the scene's own");
  Scene sc = scene;
  if (opt.method) sc.interpolation.method = *opt.method;
  if (opt.frames > 0) sc.simulation.frames = opt.frames;
  if (opt.gpu) sc.interpolation.gpu = *opt.gpu;
  return sc;
}

// 2D drag scenes may compare with the boundary-pinned variant (paper Figure 8c): a second
// pipeline with the same drags.
std::optional<pipeline::FramePipeline> pinned_pipeline(const Scene& sc, const SceneModels& m,
                                                       const interp::Embedding& emb) {
  if (sc.mode != Mode::Drag || !sc.interpolation.compare_pinned || sc.interpolation.options.pin_boundary)
    return std::nullopt;
  Scene sp = sc;
  sp.interpolation.options.pin_boundary = true;
  return make_pipeline(sp, m, emb);
}

// After the frames: the point cache completed, the 3D pictures drawn (also after a failed step:
// what was reached), metrics.json written. An error here fails the run too.
void finish_run(const Scene& sc, pipeline::FramePipeline& pipe,
                Outputs& out, Pictures3D& pictures, RunMetrics& metrics, RunResult& res) {
  try {
    out.finish();
  } catch (const std::exception& e) {
    record_failure(res, std::string("dense.pc2 or mesh.glb: ") + e.what());
  }
  const auto t0 = Clock::now();
  try {
    pictures.write(pipe);
  } catch (const std::exception& e) {
    record_failure(res, std::string("pictures: ") + e.what());
  }
  const double pictures_ms = ms_since(t0);
  // the table of the last good frame: computed with the frame when metrics are written or the
  // run reached its last frame; otherwise (a failed run without metrics) here, for the summary
  if (res.failed && !sc.output.metrics && pipe.frame() >= 0) {
    try {
      res.last_table = metrics.table();
    } catch (const std::exception&) {  // the failure is reported already
    }
  }
  metrics.finish(res, pictures_ms);
  if (sc.output.metrics) {
    try {
      metrics.write();
    } catch (const std::exception& e) {
      record_failure(res, std::string("metrics.json: ") + e.what());
    }
  }
  res.roundoff = metrics.roundoff();
}

// contact = surface: the last frame's figures (every frame's are in metrics.json).
void log_contact(pipeline::FramePipeline& pipe, const std::function<void(const std::string&)>& log) {
  const auto* sim = dynamic_cast<const pipeline::SimulatorDriver*>(&pipe.driver());
  if (!sim || !sim->contact() || pipe.frame() < 0) return;
  log("contact at the dense surface: " + std::to_string(sim->touching_points()) + " vertices inside a collider, " +
      std::to_string(sim->last_step().newton_iterations) + " Newton iterations at the last frame");
}

}  // namespace

RunResult run_scene(const Scene& scene, const RunOptions& opt) {
  const Scene sc = with_overrides(scene, opt);
  auto log = [&](const std::string& s) {
    if (opt.log) opt.log(s);
  };
  auto warn = [&](const std::string& s) {
    if (opt.warn) opt.warn(s);
    else log(s);
  };
  RunResult res;
  OutputFolder folder(sc, opt.out_dir, opt.force, input_files(sc, opt.mesh));
  res.out_dir = folder.path();

  // ---------------------------------------------------------------- models, embedding, pipeline
  auto t0 = Clock::now();
  const SceneModels m = load_models(sc, opt.mesh, opt.force_3d);
  const double load_ms = ms_since(t0);
  check_picture_size(sc, m);
  if (interp::interior_faces(m.T).rows() == 0)
    throw Error(m.control_name + ": the control mesh has no interior face (one element); a run "
                     "compares BI with modified-BI at every frame (metrics.json, pictures, and the "
                     "handles' solve in drag scenes), which needs at least two face-adjacent elements "
                     "(mbi deform --method bi or phong takes one element)");
  t0 = Clock::now();
  interp::Embedding emb = interp::embed(m.U, m.T, m.dense.V);
  const double embed_ms = ms_since(t0);
  const std::size_t outside = emb.outside.size();
  res.outside_points = static_cast<int>(outside);
  if (outside > 0)
    warn("warning: " + std::to_string(outside) + " dense vertices lie outside the control mesh (farthest " +
         format_num(emb.max_outside_distance) + "); they follow the nearest element by extrapolation");
  std::optional<pipeline::FramePipeline> pinned = pinned_pipeline(sc, m, emb);
  Evaluation evaluation = make_evaluator(sc.interpolation.gpu, warn);
  pipeline::FramePipeline pipe = make_pipeline(sc, m, std::move(emb), std::move(evaluation.evaluator));
  res.evaluator = pipe.evaluator().name();
  Pictures3D pictures(sc, m, folder.path(), evaluation.context);
  RunMetrics metrics(sc, m, pipe, outside, pictures.renderer(), load_ms, embed_ms, folder.path());
  log("dense: " + m.dense_name + " (" + std::to_string(m.dense.V.rows()) + " vertices)");
  log("control: " + m.control_name + ": " + std::to_string(m.U.rows()) + " vertices, " +
      std::to_string(m.T.rows()) + (m.dim() == 3 ? " tetrahedra" : " triangles"));

  // ---------------------------------------------------------------- frames
  if (opt.stop && opt.stop->load() != 0) {  // interrupted while loading: nothing written
    res.interrupted = opt.stop->load();
    res.frames = -1;
    return res;
  }
  folder.make();
  Outputs out(sc, m, folder.path());
  FrameLoop(sc, pipe, pinned ? &*pinned : nullptr, out, pictures, metrics).run(res, opt.progress, opt.stop);
  finish_run(sc, pipe, out, pictures, metrics, res);
  log_contact(pipe, log);
  return res;
}

std::string signal_name(int signal) {
  if (signal == SIGINT) return "SIGINT";
  if (signal == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signal);
}

}  // namespace mbi::scenes
