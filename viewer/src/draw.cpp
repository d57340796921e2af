#include "draw.hpp"

#include "colliders.hpp"
#include "crease_layer.hpp"
#include "scenery.hpp"

#include <algorithm>
#include <chrono>
#include <mbi/base/timer.hpp>
#include <mbi/gpu/window.hpp>

namespace mbi::viewer {
namespace {

// The markers of direct mode (handles big, every control vertex small) and of the poke target.
void draw_markers(gpu::Renderer& renderer, const Interaction& in, const ViewerOptions& options,
                  const Eigen::MatrixXd& X3, const Eigen::Matrix4d& vp) {
  if (options.handles && in.direct() && !in.handles().empty()) {
    Eigen::MatrixXd H(static_cast<Eigen::Index>(in.handles().size()), 3);
    for (size_t h = 0; h < in.handles().size(); ++h) H.row(static_cast<Eigen::Index>(h)) = X3.row(in.handles()[h]);
    renderer.draw_points(H, vp, {0.1, 0.35, 0.9}, 9.0f);
  }
  if (options.handles && in.direct()) renderer.draw_points(X3, vp, {0.3, 0.3, 0.3}, 4.0f);
  if (in.poke().handle >= 0) {
    Eigen::MatrixXd P(1, 3);
    P.row(0) = in.poke().target.transpose();
    renderer.draw_points(P, vp, {0.85, 0.1, 0.1}, 8.0f);
  }
}

}  // namespace

void draw_views(gpu::Renderer& renderer, Stage& stage, const Interaction& in, const Camera& camera,
                const ViewerOptions& options, const Eigen::MatrixXd& X3, int fb_width, int fb_height,
                FrameTimes& times, bool looks) {
  const auto started = Clock::now();
  gpu::clear_window(fb_width, fb_height, looks ? kBackground : Eigen::Vector3d(1, 1, 1));
  const Eigen::Vector3d color(0.85, 0.62, 0.35);
  const bool creases = options.creases && stage.d == 3;
  if (creases) {  // the CPU's share only while on
    if (!stage.creases) stage.creases = std::make_shared<CreaseLayer>(stage);
    stage.creases->update(stage);
  }
  if (stage.creases) stage.creases->shown = creases;
  const bool scenery = looks && stage.d == 3;
  if (scenery && !stage.ground) stage.ground = std::make_shared<Ground>(ground_at_rest(stage.U, stage.rest_dense, options.up));
  Ground ground = scenery ? *stage.ground : Ground{};
  if (scenery) cast_shadow(ground, X3);
  const CollidersNow colliders = colliders_now(stage, scenery ? &ground : nullptr, options.up);
  const int n = static_cast<int>(stage.views.size());
  double gpu_ms = 0;
  for (int k = 0; k < n; ++k) {
    const Rect& vp_rect = stage.layout.view_viewports[static_cast<size_t>(k)];
    const int x0 = static_cast<int>(vp_rect.x), x1 = static_cast<int>(vp_rect.x + vp_rect.w);
    gpu::viewport(x0, 0, x1 - x0, fb_height);
    stage.evaluator.evaluate(stage.pipe.bezier_with(stage.views[static_cast<size_t>(k)]), stage.d == 3);
    gpu_ms += stage.evaluator.timings().upload_ms + stage.evaluator.timings().pass_ms;
    const Eigen::Matrix4d vp = camera.view_projection(static_cast<double>(x1 - x0) / std::max(fb_height, 1));
    if (scenery) renderer.draw_ground(ground, vp);
    if (scenery && !creases) renderer.draw_material(stage.gpu, vp, view_rotation(camera), color);
    // with the looks draw() only adds the wireframe: its surface lies behind the material's
    if (stage.d == 3 && (!creases || options.wireframe) && (!scenery || options.wireframe))
      renderer.draw(stage.gpu, vp, camera.direction(), color, options.wireframe ? &X3 : nullptr,
                    options.wireframe ? &stage.T : nullptr);
    if (creases)
      renderer.draw_colors(stage.gpu, vp, camera.direction(), stage.creases->views()[static_cast<size_t>(k)].rgb);
    if (stage.d == 2)
      renderer.draw_textured(stage.gpu, vp, *stage.image);
    if (stage.d == 3) draw_colliders(renderer, colliders, in.grabbed_collider(), vp, camera.direction());
    draw_markers(renderer, in, options, X3, vp);
  }
  gpu::viewport(0, 0, fb_width, fb_height);
  gpu::finish();
  times.interpolation_ms = gpu_ms;
  times.drawing_ms = ms_since(started) - gpu_ms;
  const double dt = ms_since(times.last_frame);
  times.last_frame = Clock::now();
  times.fps = dt > 0 ? 0.9 * times.fps + 0.1 * 1000.0 / dt : times.fps;
}

}  // namespace mbi::viewer
