#include "interaction.hpp"

#include <mbi/interact/collider.hpp>
#include <mbi/interp/control.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

namespace mbi::viewer {

Interaction::Interaction(Stage& stage, Camera& camera, const ViewerOptions& options)
    : stage_(stage), camera_(camera), opt_(options) {}

void Interaction::press(double x, double y, int button, const WindowSize& window) {
  last_x_ = x, last_y_ = y;
  if (x >= panel_min.x() && x <= panel_max.x() && y >= panel_min.y() && y <= panel_max.y())
    return;  // on the panel: not a poke
  const int view = view_at(x, window);
  view_of_drag_ = view;
  if (button == 1) {  // right: remove a handle, else pan
    if (!(direct_ && remove_handle(nearest_control_vertex(x, y, view, window)))) drag_ = Drag::Pan;
    return;
  }
  if (button == 2) {
    drag_ = Drag::Pan;
    return;
  }
  if (direct_) {
    if (grab_handle(nearest_control_vertex(x, y, view, window))) return;
  } else if (stage_.simulation() && stage_.d == 3) {
    if (grab_under(x, y, view, window)) return;
  }
  drag_ = stage_.d == 2 ? Drag::Pan : Drag::Orbit;
}

void Interaction::move(double x, double y, const WindowSize& window) {
  const double dx = x - last_x_, dy = y - last_y_;
  last_x_ = x, last_y_ = y;
  if (drag_ == Drag::Orbit) camera_.orbit(dx, dy);
  if (drag_ == Drag::Pan) camera_.pan(dx, dy, window.height);
  if (drag_ == Drag::Poke && poke_.handle >= 0 && stage_.simulation()) {
    poke_.target =
        poke_target(ray_at(x, y, view_of_drag_, window), poke_.point, camera_.direction(), 0.5 * stage_.size);
    stage_.simulation()->simulator().set_poke_target(poke_.handle, poke_.target);
  }
  if (drag_ == Drag::Collider)  // as far as a poke's target may go, but from the collider's grab
    collider_target_ = poke_target(ray_at(x, y, view_of_drag_, window), collider_grab_, camera_.direction(), 2 * stage_.size);
  if (drag_ == Drag::Handle && dragged_handle_ >= 0 && dragged_handle_ < static_cast<int>(handles_.size())) {
    const Eigen::Index k = dragged_handle_;
    const Eigen::Vector3d from = pad3(handle_targets_.row(k));
    const Eigen::Vector3d to =
        poke_target(ray_at(x, y, view_of_drag_, window), from, camera_.direction(), 10 * stage_.size);
    handle_targets_.row(k) = to.head(stage_.d).transpose();
    if (auto* hd = dynamic_cast<pipeline::HandleDriver*>(&stage_.pipe.driver())) hd->set_targets(handle_targets_);
  }
}

void Interaction::release() {
  if (drag_ == Drag::Poke) release_poke();
  drag_ = Drag::None;
  dragged_handle_ = -1;
}

void Interaction::scroll(double dy) { camera_.zoom(dy); }

void Interaction::set_direct(bool on) {
  if (on == direct_) return;
  release_poke();
  if (drag_ == Drag::Collider) drag_ = Drag::None;
  direct_ = on;
  if (on) {
    handles_.clear();
    handle_targets_.resize(0, stage_.d);
    auto given = std::make_unique<pipeline::GivenDriver>(stage_.U);
    given->set(stage_.pipe.control_positions());
    saved_driver_ = stage_.pipe.set_driver(std::move(given));
  } else if (saved_driver_) {
    stage_.pipe.set_driver(std::move(saved_driver_));
  }
}

void Interaction::release_poke() {
  pipeline::SimulatorDriver* sim = stage_.simulation();
  if (poke_.handle >= 0 && sim && sim->simulator().has_handle(poke_.handle)) sim->simulator().remove(poke_.handle);
  poke_.handle = -1;
}

void Interaction::carry_collider(double dt) {
  pipeline::SurfaceContact* contact = stage_.contact();
  if (drag_ != Drag::Collider || !contact) return;
  const size_t i = static_cast<size_t>(grabbed_collider_);
  contact->set_collider(i, interact::dragged(contact->colliders()[i], stage_.time(), collider_target_ - collider_carried_, dt));
  collider_carried_ = collider_target_;
}

void Interaction::reset() {
  release_poke();
  if (drag_ == Drag::Collider) drag_ = Drag::None;
  stage_.pipe.reset();
  pipeline::SurfaceContact* contact = stage_.contact();
  if (contact && contact->colliders().size() == stage_.scene_colliders.size())
    for (size_t i = 0; i < stage_.scene_colliders.size(); ++i) contact->set_collider(i, stage_.scene_colliders[i]);
  stage_.pipe.step(false);
}

int Interaction::view_at(double x, const WindowSize&) const { return stage_.view_at(x); }

Ray Interaction::ray_at(double x, double y, int view, const WindowSize& window) const {
  const Rect& r = stage_.layout.views[static_cast<size_t>(view)];
  return camera_.ray(x - r.x, y, static_cast<int>(std::lround(r.w)), window.height);
}

int Interaction::nearest_control_vertex(double x, double y, int view, const WindowSize& window) const {
  const Eigen::MatrixXd X3 = stage_.control_positions_3d();
  const Rect& r = stage_.layout.views[static_cast<size_t>(view)];
  int best = -1;
  double best_d = 12.0;  // pixels
  for (Eigen::Index i = 0; i < X3.rows(); ++i) {
    const Eigen::Vector2d q = camera_.project(X3.row(i).transpose(), static_cast<int>(std::lround(r.w)), window.height);
    const double dist = (q - Eigen::Vector2d(x - r.x, y)).norm();
    if (dist < best_d) best_d = dist, best = static_cast<int>(i);
  }
  return best;
}

bool Interaction::remove_handle(int vertex) {
  auto it = std::find(handles_.begin(), handles_.end(), vertex);
  if (vertex < 0 || it == handles_.end()) return false;
  const auto k = it - handles_.begin();
  handles_.erase(it);
  Eigen::MatrixXd t(handle_targets_.rows() - 1, stage_.d);
  for (Eigen::Index r = 0, w = 0; r < handle_targets_.rows(); ++r)
    if (r != k) t.row(w++) = handle_targets_.row(r);
  handle_targets_ = t;
  use_handles();
  return true;
}

bool Interaction::grab_handle(int vertex) {
  if (vertex < 0) return false;
  auto it = std::find(handles_.begin(), handles_.end(), vertex);
  if (it == handles_.end()) {
    handles_.push_back(vertex);
    handle_targets_.conservativeResize(static_cast<Eigen::Index>(handles_.size()), stage_.d);
    handle_targets_.row(handle_targets_.rows() - 1) = stage_.pipe.control_positions().row(vertex);
    use_handles();
    it = handles_.end() - 1;
  }
  dragged_handle_ = static_cast<int>(it - handles_.begin());
  drag_ = Drag::Handle;
  return true;
}

bool Interaction::grab_under(double x, double y, int view, const WindowSize& window) {
  const Ray ray = ray_at(x, y, view, window);
  if (!ray.origin.allFinite()) return false;  // a cursor far outside the window picks nothing
  Eigen::MatrixXd V;
  stage_.pipe.evaluate_with(stage_.views[static_cast<size_t>(view)], V);
  const std::optional<Hit> model = cast(ray, V, stage_.F);
  const pipeline::SurfaceContact* contact = stage_.contact();
  const std::optional<interact::ColliderHit> collider =
      contact ? interact::pick_collider(ray, contact->colliders(), stage_.time()) : std::nullopt;
  if (collider && (!model || collider->hit.t < model->t)) {
    release_poke();
    grabbed_collider_ = collider->collider;
    collider_grab_ = collider_target_ = collider_carried_ = collider->hit.point;
    drag_ = Drag::Collider;
    return true;
  }
  if (!model) return false;
  start_poke(*model);
  return true;
}

void Interaction::start_poke(const Hit& hit) {
  sim::Simulator& sim = stage_.simulation()->simulator();
  Poke p;
  static_cast<interact::Grab&>(p) =
      interact::grab(hit, stage_.rest_dense, stage_.F, stage_.U, stage_.T, sim.masses(), opt_.poke_response);
  p.target = p.point;
  release_poke();
  p.handle = sim.add_poke(p.element, p.bary, p.target, p.stiffness);
  poke_ = p;
  drag_ = Drag::Poke;
}

void Interaction::use_handles() {
  if (handles_.empty()) {
    auto given = std::make_unique<pipeline::GivenDriver>(stage_.U);
    given->set(stage_.pipe.control_positions());
    stage_.pipe.set_driver(std::move(given));
    return;
  }
  interp::ControlOptions co;
  co.interp.alpha = stage_.alpha;
  auto driver = std::make_unique<pipeline::HandleDriver>(stage_.U, stage_.T, handles_, co);
  driver->set_targets(handle_targets_);
  stage_.pipe.set_driver(std::move(driver));
}
}  // namespace mbi::viewer
