#include "crease_layer.hpp"

#include <algorithm>

namespace mbi::viewer {

CreaseLayer::CreaseLayer(const Stage& stage)
    : creases_(stage.U, stage.T),
      near_(creases_.near_faces(stage.pipe.embedding())) {}

void CreaseLayer::update(Stage& stage) {
  std::vector<Eigen::VectorXd> jumps;
  top_ = 0;
  for (pipeline::Method m : stage.views) {
    jumps.push_back(creases_.face_jumps(stage.pipe, m));
    if (jumps.back().size()) top_ = std::max(top_, jumps.back().maxCoeff());
  }
  const double top = pipeline::crease_scale(top_);
  views_.resize(jumps.size());
  for (size_t k = 0; k < jumps.size(); ++k) {
    const Eigen::VectorXd v = creases_.point_values(stage.pipe.embedding(), jumps[k]);
    CreaseView& cv = views_[k];
    cv.rgb.resize(static_cast<size_t>(v.size()) * 3);
    cv.mean_jump = jumps[k].size() ? jumps[k].mean() : 0.0;
    double near_sum = 0;
    long near_count = 0;
    for (Eigen::Index q = 0; q < v.size(); ++q) {
      const Eigen::Vector3d c = pipeline::crease_color(v(q) / top);
      for (int i = 0; i < 3; ++i) cv.rgb[static_cast<size_t>(3 * q + i)] = static_cast<float>(c(i));
      if (near_[static_cast<size_t>(q)]) near_sum += std::min(v(q) / top, 1.0), ++near_count;
    }
    cv.mean_near = near_count ? near_sum / static_cast<double>(near_count) : 0.0;
  }
}

}  // namespace mbi::viewer
