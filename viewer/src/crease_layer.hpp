#pragma once
// The creases in colour in the viewer (internal): while the toggle is on, each frame computes
// every view's face jumps on the CPU (mbi/pipeline/creases.hpp), one scale for all views, and draws the
// dense surface from the evaluator's buffers with a colour per vertex. Nothing runs while off.
#include "stage.hpp"

#include <mbi/gpu/evaluator.hpp>
#include <mbi/gpu/surface.hpp>
#include <mbi/pipeline/creases.hpp>

#include <vector>

namespace mbi::viewer {

/// One view's crease colours and what the report says of them.
struct CreaseView {
  std::vector<float> rgb;  ///< per dense point, 0..1
  double mean_jump = 0;    ///< mean face jump of the view's method (pipeline::Creases::face_jumps)
  double mean_near = 0;    ///< mean scale position (0..1) of the dense points near interior faces
};

class CreaseLayer {
 public:
  /// Needs the viewer's OpenGL context current. Throws Error when its shaders fail.
  CreaseLayer(const Stage& stage);
  ~CreaseLayer();
  CreaseLayer(const CreaseLayer&) = delete;
  CreaseLayer& operator=(const CreaseLayer&) = delete;

  /// This frame's colours of stage.views on one shared scale.
  void update(Stage& stage);
  /// Draws view k's surface from `ev`'s buffers (as gpu::Renderer::draw, coloured per vertex),
  /// slightly in front of a surface drawn there already (the wireframe pass).
  void draw(const gpu::GpuEvaluator& ev, size_t k, const Eigen::Matrix4d& view_projection,
            const Eigen::Vector3d& eye_direction);

  double top() const { return top_; }  ///< the scale's top: the largest face jump of the views
  const std::vector<CreaseView>& views() const { return views_; }
  Rect legend;         ///< where the panel drew the legend's bar (logical pixels); w = 0 before
  bool shown = false;  ///< updated and drawn this frame (the toggle is on)

 private:
  pipeline::Creases creases_;
  std::vector<bool> near_;
  std::vector<CreaseView> views_;
  double top_ = 0;
  gpu::Surface surface_;
  unsigned program_ = 0;
};

}  // namespace mbi::viewer
