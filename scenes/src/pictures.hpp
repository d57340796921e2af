#pragma once
// The pictures of a run (frame_NNNN.png at the written frames): the run's panels side by side,
// BI | modified-BI, or BI | Phong | modified-BI for a Phong run. 2D pictures warp the scene's
// image and are written with each frame (Outputs); 3D pictures are drawn at the end of the run
// (Pictures3D), on the GPU when the run evaluates there, else by the CPU rasteriser.
#include <mbi/interp/modified_bi.hpp>
#include <mbi/io/scratch_file.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/raster/raster.hpp>
#include <mbi/pipeline/creases.hpp>
#include <mbi/scenes/runner.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <filesystem>
#include <memory>
#include <vector>

namespace mbi::gpu {
class Context;
class Renderer;
}  // namespace mbi::gpu

namespace mbi::scenes {

/// The methods of a picture's panels, left to right, for a run of `method`.
std::vector<pipeline::Method> picture_methods(pipeline::Method method);

/// Pictures that could not be written fail at load, not after frame 0: 2D panels are the
/// image's size x 1.5 each, side by side with 8-pixel gaps; io::Image holds at most 16384 x
/// 16384. Throws Error.
void check_picture_size(const Scene& sc, const SceneModels& m);

/// The 3D pictures of a run: the Bezier points of each written frame's panels wait in a scratch
/// file in the output folder (io::ScratchFile: about 240 bytes a tetrahedron a panel, on disk,
/// so memory stays the same however many frames run), and the pictures are drawn at the end,
/// all the same size, with one camera that frames the control mesh over the whole run and the
/// colliders near it. Each picture shows the run's colliders at that frame's pose (grey-blue)
/// and its ground (a grey checked square); a run without them draws the model alone.
class Pictures3D {
 public:
  /// `context`: the run's GPU evaluator's, whose buffers the pictures are drawn from; null: the
  /// CPU rasteriser.
  Pictures3D(const Scene& sc, const SceneModels& m, const std::filesystem::path& dir,
             std::shared_ptr<gpu::Context> context);
  ~Pictures3D();
  Pictures3D(const Pictures3D&) = delete;
  Pictures3D& operator=(const Pictures3D&) = delete;

  /// What draws them: "gpu" or "cpu".
  const char* renderer() const;
  /// Frame f's panels (Bezier points, picture_methods of pipe's method) at pipe's control
  /// positions, with each panel's face jumps when output.creases: stored whole, or not at all
  /// (throws io::Error when the disk is full).
  void add(int f, pipeline::FramePipeline& pipe, const std::vector<interp::BezierPoints>& panels);
  /// Forgets the frame add() stored last (a later part of that frame failed).
  void discard_last();
  /// Draws and writes every stored picture (the pipeline's evaluator and embedding evaluate them).
  void write(pipeline::FramePipeline& pipe);

 private:
  /// The frame stored at byte `at` of the scratch file, its time, its panels' face jumps
  /// (output.creases); `at` moves past it.
  int read_frame(long& at, double& time, std::vector<interp::BezierPoints>& panels,
                 std::vector<Eigen::VectorXd>& jumps) const;
  /// One panel coloured by its creases (CPU), on the run's shared scale.
  io::Image crease_panel(pipeline::FramePipeline& pipe, const interp::BezierPoints& B, const Eigen::VectorXd& jumps,
                         const raster::View& view, int w, int h) const;

  const Scene& sc_;
  const SceneModels& m_;
  std::filesystem::path dir_;
  std::shared_ptr<gpu::Context> context_;
  std::unique_ptr<gpu::Renderer> renderer_;
  Eigen::Vector3d lo_, hi_, lo_before_, hi_before_;  // bounds, and before the last add()
  std::unique_ptr<io::ScratchFile> stored_;          // made at the first add()
  long last_at_ = 0;                                 // where the last frame stored starts
  std::unique_ptr<pipeline::Creases> creases_;                 // output.creases only
  double top_ = 0, top_before_ = 0;                  // the largest face jump stored, and before the last add()
  Eigen::AlignedBox3d near_, near_before_;           // the colliders near the model, and before the last add()
};

}  // namespace mbi::scenes
