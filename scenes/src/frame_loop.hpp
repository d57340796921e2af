#pragma once
// The frames of a run: each steps the pipeline (and the boundary-pinned comparison), records its
// metrics and writes its outputs. A failing step, or an error while writing a frame (a result
// that does not fit a file, a full disk), ends the run (exit 3): every output written so far is
// kept, and metrics.json tells how far the run got. A frame is kept whole or not at all: when
// one of its outputs cannot be written, the others of that frame are taken back, so that
// dense.pc2, the pictures and metrics.json hold the same frames.
#include "metrics.hpp"
#include "outputs.hpp"
#include "pictures.hpp"

#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/scenes/runner.hpp>

#include <atomic>
#include <functional>
#include <string>
#include <vector>

namespace mbi::scenes {

/// Records the failure that ends a run: the first one (later ones follow from it).
void record_failure(RunResult& res, const std::string& what);

class FrameLoop {
 public:
  /// pinned: the boundary-pinned comparison of a 2D drag scene, or null.
  FrameLoop(const Scene& sc, pipeline::FramePipeline& pipe, pipeline::FramePipeline* pinned,
            Outputs& out, Pictures3D& pictures, RunMetrics& metrics)
      : sc_(sc), pipe_(pipe), pinned_(pinned), out_(out), pictures_(pictures), metrics_(metrics) {}

  /// Frames 0 to sc.simulation.frames, until one fails or `stop` (may be null) becomes
  /// non-zero (then the next frame is the last, written whole, and res.interrupted is set); res.frames: the last one completed, res.last_table: its
  /// discontinuity table (when computed: metrics on, or the last frame).
  void run(RunResult& res, const std::function<void(int, int)>& progress, const std::atomic<int>* stop);

 private:
  /// Frame f (the run's last when `stopping`); false when its step failed (recorded in res).
  /// Throws on any other error.
  bool frame(int f, RunResult& res, bool stopping);
  /// The 2D picture's panels (picture_methods, then the pinned comparison).
  std::vector<const Eigen::MatrixXd*> panels_2d();
  /// The 3D picture's panels, drawn after the run from their Bezier points.
  std::vector<interp::BezierPoints> panels_3d();

  const Scene& sc_;
  pipeline::FramePipeline& pipe_;
  pipeline::FramePipeline* pinned_;
  Outputs& out_;
  Pictures3D& pictures_;
  RunMetrics& metrics_;
  std::vector<Eigen::MatrixXd> others_;  // the 2D picture's methods other than the run's
};

}  // namespace mbi::scenes
