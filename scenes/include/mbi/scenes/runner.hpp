#pragma once
// The headless scene runner behind `mbi run`: loads a scene's models, builds its frame pipeline
// (simulation or drags, method, alpha) and writes the outputs of each frame:
//   <out>/mesh_NNNN.obj|ply    dense mesh at the written frames (every output.every, and last)
//   <out>/dense.pc2            point cache of every frame (Blender Mesh Cache, 3ds Max)
//   <out>/control_NNNN.vtk     control mesh at the written frames (ParaView)
//   <out>/frame_NNNN.png       pictures: 3D BI | modified-BI side by side (BI | Phong | modified-BI
//                              for method phong; GPU or CPU renderer, one size and one camera
//                              for the whole run); 2D the warped image
//   <out>/metrics.json         per-frame timings and the discontinuity table (BI vs modified-BI,
//                              and Phong for method phong)
// The output folder and its rules: output_folder.hpp; what evaluates the dense points (GPU or
// CPU): evaluator.hpp.
#include <mbi/interp/metrics.hpp>
#include <mbi/scenes/models.hpp>
#include <mbi/scenes/scene.hpp>

#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace mbi::scenes {

struct RunOptions {
  std::filesystem::path out_dir;         ///< empty: "out/<scene name>"
  int frames = 0;                        ///< 0: the scene's
  std::filesystem::path mesh;            ///< replaces the scene's dense model
  std::optional<pipeline::Method> method;  ///< replaces the scene's
  bool force = false;                    ///< overwrite a non-empty output folder
  bool force_3d = false;                 ///< a flat dense model stays 3D (load_models)
  std::optional<GpuUse> gpu;             ///< replaces the scene's interpolation.gpu
  /// Progress callback (frame done, frames total); may be empty.
  std::function<void(int, int)> progress;
  /// Log lines (summary); may be empty.
  std::function<void(const std::string&)> log;
  /// Notes the user must see even when quiet (outside points, no OpenGL under gpu = auto); may be
  /// empty (then they go to `log`).
  std::function<void(const std::string&)> warn;
  /// When it becomes non-zero (a signal number, set by a signal handler), the run stops after
  /// the frame in progress and finishes its outputs up to that frame; before the first frame,
  /// it ends with nothing written. May be null.
  const std::atomic<int>* stop = nullptr;
};

struct RunResult {
  std::filesystem::path out_dir;
  int frames = 0;         ///< frames completed
  bool failed = false;    ///< a simulation step failed; outputs up to the last good frame kept
  std::string message;    ///< the failure
  int interrupted = 0;    ///< the signal that stopped the run (RunOptions::stop), or 0
  mbi::interp::DiscontinuityTable last_table;  ///< of the last completed frame
  int outside_points = 0;
  std::string evaluator;  ///< what evaluated the dense points, e.g. "gpu (llvmpipe ...)"
  double roundoff = 0;    ///< round-off level of the discontinuities (report.hpp disc_roundoff)
};

/// Runs a scene headless. Throws on bad input before anything is written (mbi::Error: Error,
/// io::Error, interp::Error, sim::Error). A failing simulation step ends the run with
/// RunResult::failed and keeps what was written; RunOptions::stop ends it with
/// RunResult::interrupted.
///
/// Memory stays bounded however many frames run: the per-frame records of metrics.json and the
/// Bezier points of the 3D pictures wait in unnamed scratch files in the output folder (on its
/// disk, gone when the process ends), not in memory.
RunResult run_scene(const Scene& scene, const RunOptions& options);

/// "SIGINT", "SIGTERM", or "signal N".
std::string signal_name(int signal);

}  // namespace mbi::scenes
