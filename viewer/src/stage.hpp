#pragma once
// What one Viewer::show displays and how (internal): the pipeline, the views side by side (BI |
// the pipeline's method), the model's bounds for the camera; and the small state the parts of
// the viewer share (window size, run flags, frame times).
#include <mbi/viewer/camera.hpp>
#include <mbi/viewer/layout.hpp>
#include <mbi/viewer/viewer.hpp>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

namespace mbi::viewer {

class CreaseLayer;
struct Ground;

/// The window's size in logical pixels (what GLFW reports; at least 1 x 1).
struct WindowSize {
  int width = 1, height = 1;
};

/// What keys and the panel ask of the frame loop, and the line the panel shows.
struct Controls {
  bool step_once = false, help = false, close = false;
  bool collapsed = false;        ///< the panel folded to a strip (c key, its title bar's arrow)
  bool toggle_collapse = false;  ///< the c key, for the panel's next frame
  bool snapshot = false;         ///< the p key: this frame's picture to a file
  std::string message;  ///< shown in the panel (errors, screenshots)
};

/// The last frame's times (ms) and the smoothed frame rate (the panel and the report show them).
struct FrameTimes {
  double interpolation_ms = 0, drawing_ms = 0, fps = 0;
  std::chrono::steady_clock::time_point last_frame = std::chrono::steady_clock::now();
};

/// A row of d <= 3 coordinates as a 3D point (z = 0 in 2D).
inline Eigen::Vector3d pad3(const Eigen::RowVectorXd& r) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  p.head(r.size()) = r.transpose();
  return p;
}

struct Stage {
  /// Throws Error: a pipeline not built with Viewer::evaluator(), 2D without an image.
  explicit Stage(const Shown& shown);

  pipeline::FramePipeline& pipe;
  pipeline::Evaluator& evaluator;  ///< the pipeline's: the GPU pass or a DrawnEvaluator
  gpu::GpuEvaluator& gpu;          ///< the buffers drawn
  std::string evaluator_why;       ///< why this evaluator (the HUD)
  std::string looks;               ///< the looks in use (kLooksNames; the report)
  const Eigen::MatrixXi& F;
  const io::Image* image;
  const int d;                     ///< 2 or 3
  const Eigen::MatrixXd& U;        ///< rest control positions, n x d
  const Eigen::MatrixXi& T;        ///< control elements
  const Eigen::MatrixXd rest_dense;  ///< the dense points at rest
  Eigen::Vector3d lo, hi;          ///< the control mesh's bounds (z = 0 in 2D)
  double size;                     ///< their diagonal
  double alpha;                    ///< interpolation weight shown in the panel
  sim::Material material;          ///< edited in the panel
  std::function<std::unique_ptr<pipeline::Driver>(const sim::Material&)> rebuild;
  std::vector<pipeline::Method> views;  ///< left to right
  /// The creases in colour (options.creases, 3D): made when first shown, kept while the stage is
  std::shared_ptr<CreaseLayer> creases;
  /// The looks' ground under the model at rest: made when first drawn, kept while the stage is
  std::shared_ptr<Ground> ground;

  void set_views(bool split);
  void set_method(pipeline::Method method, bool split);
  /// The interpolation weight, kept within [kMinAlpha, kMaxAlpha] (the panel slider's range).
  void set_alpha(double a);
  static constexpr double kMinAlpha = 0.001, kMaxAlpha = 1.0;
  /// The camera framing the control mesh; 2D looks at the picture from the front (y down).
  void frame(Camera& camera, const Eigen::Vector3d& up) const;
  /// The pipeline's driver when it is a simulation, else nullptr.
  pipeline::SimulatorDriver* simulation() const;
  /// The simulation's surface contact, on or switched off (kept in `parked`); else nullptr.
  pipeline::SurfaceContact* contact() const;
  bool contact_on() const;
  /// Contact on or off from the next step on (a simulation with surface contact; else nothing).
  void set_contact(bool on);
  /// The simulation's time (s; 0 without one): the colliders' pose drawn and dragged.
  double time() const;
  std::vector<pipeline::Collider> scene_colliders;  ///< as the scene gave them: reset puts them back
  std::shared_ptr<pipeline::SurfaceContact> parked;  ///< the contact while switched off
  /// The current control positions, n x 3 (z = 0 in 2D).
  Eigen::MatrixXd control_positions_3d() const;
  Layout layout;  ///< this frame's: the panel and the views (the Viewer sets it)
  /// The view under window column x (logical pixels), clamped to the views.
  int view_at(double x) const;
};

}  // namespace mbi::viewer
