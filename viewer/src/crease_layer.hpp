#pragma once
// The creases in colour in the viewer (internal): while the toggle is on, each frame computes
// every view's face jumps on the CPU (mbi/pipeline/creases.hpp), one scale for all views: the
// colours per dense point that gpu::Renderer::draw_colors draws. Nothing runs while off.
#include "stage.hpp"

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
  explicit CreaseLayer(const Stage& stage);

  /// This frame's colours of stage.views on one shared scale.
  void update(Stage& stage);

  double top() const { return top_; }  ///< the scale's top: the largest face jump of the views
  const std::vector<CreaseView>& views() const { return views_; }
  Rect legend;         ///< where the panel drew the legend's bar (logical pixels); w = 0 before
  bool shown = false;  ///< updated and drawn this frame (the toggle is on)

 private:
  pipeline::Creases creases_;
  std::vector<bool> near_;
  std::vector<CreaseView> views_;
  double top_ = 0;
};

}  // namespace mbi::viewer
