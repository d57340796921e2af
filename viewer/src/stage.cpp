#include "stage.hpp"

#include "evaluation.hpp"

#include <mbi/interp/embed.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <algorithm>
#include <cmath>

namespace mbi::viewer {
namespace {

gpu::GpuEvaluator& gpu_evaluator(pipeline::FramePipeline& pipe) {
  auto* gpu = dynamic_cast<gpu::GpuEvaluator*>(&pipe.evaluator());
  if (auto* drawn = dynamic_cast<DrawnEvaluator*>(&pipe.evaluator())) gpu = &drawn->buffers();
  if (!gpu) throw Error("the viewer shows pipelines built with Viewer::evaluator()");
  return *gpu;
}

const io::Image* checked_image(const Shown& shown) {
  if (shown.pipe.dim() == 2 && !shown.image) throw Error("a 2D pipeline needs an image to draw");
  return shown.image;
}

}  // namespace

Stage::Stage(const Shown& shown)
    : pipe(shown.pipe),
      evaluator(shown.pipe.evaluator()),
      gpu(gpu_evaluator(shown.pipe)),
      F(shown.faces),
      image(checked_image(shown)),
      d(pipe.dim()),
      U(pipe.rest_positions()),
      T(pipe.elements()),
      rest_dense(interp::embedded_positions(U, T, pipe.embedding())),
      material(shown.material),
      rebuild(shown.rebuild) {
  lo = hi = Eigen::Vector3d::Zero();
  lo.head(d) = U.colwise().minCoeff().transpose();
  hi.head(d) = U.colwise().maxCoeff().transpose();
  size = (hi - lo).norm();
  alpha = interp::resolve_alpha(pipe.options().interp, d);
  if (const pipeline::SurfaceContact* c = contact()) scene_colliders = c->colliders();
}

void Stage::set_views(bool split) {
  views.clear();
  if (split && pipe.method() != pipeline::Method::BI) views.push_back(pipeline::Method::BI);
  views.push_back(pipe.method());
}

void Stage::set_method(pipeline::Method method, bool split) {
  pipe.set_method(method);
  set_views(split);
}

void Stage::set_alpha(double a) {
  if (!std::isfinite(a)) return;
  alpha = std::clamp(a, kMinAlpha, kMaxAlpha);
  pipe.set_alpha(alpha);
}

void Stage::frame(Camera& camera, const Eigen::Vector3d& up) const {
  if (d == 2) {
    camera.frame(lo, hi, Eigen::Vector3d(0, -1, 0));
    camera.yaw = std::acos(-1.0);
    camera.pitch = 0;
  } else {
    camera.frame(lo, hi, up);
    camera.yaw = 0.6;
    camera.pitch = 0.35;
  }
}

pipeline::SimulatorDriver* Stage::simulation() const {
  return dynamic_cast<pipeline::SimulatorDriver*>(&pipe.driver());
}

pipeline::SurfaceContact* Stage::contact() const {
  const pipeline::SimulatorDriver* sd = simulation();
  if (!sd) return nullptr;
  return sd->contact() ? sd->contact().get() : parked.get();
}

bool Stage::contact_on() const {
  const pipeline::SimulatorDriver* sd = simulation();
  return sd && sd->contact();
}

void Stage::set_contact(bool on) {
  pipeline::SimulatorDriver* sd = simulation();
  if (!sd || on == contact_on() || !contact()) return;
  if (on) {
    sd->set_contact(parked);
    parked.reset();
  } else {
    parked = sd->contact();
    sd->set_contact(nullptr);
  }
}

double Stage::time() const {
  const pipeline::SimulatorDriver* sd = simulation();
  return sd ? sd->simulator().time() : 0.0;
}

Eigen::MatrixXd Stage::control_positions_3d() const {
  Eigen::MatrixXd X3 = Eigen::MatrixXd::Zero(U.rows(), 3);
  X3.leftCols(d) = pipe.control_positions();
  return X3;
}

int Stage::view_at(double x) const {
  const int n = static_cast<int>(layout.views.size());
  int k = 0;
  while (k + 1 < n && x >= layout.views[static_cast<size_t>(k + 1)].x) ++k;
  return k;
}

}  // namespace mbi::viewer
