#pragma once
// The mouse on the model (internal): picking in the view under the cursor, pokes (grab the
// surface, a bounded spring pulls the grabbed material point to the cursor), direct mode (click
// control vertices to make them handles and drag them; no physics), orbit, pan and zoom.
// Coordinates are window coordinates (logical pixels, y down).
#include "stage.hpp"

#include <memory>
#include <vector>

namespace mbi::viewer {

/// A poke spring on the simulation: the grabbed material point (element, barycentric
/// coordinates, stiffness; the drag plane passes through `point`) pulled toward `target`.
struct Poke : interact::Grab {
  int handle = -1;   ///< the simulator's handle; -1: no poke
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
};

class Interaction {
 public:
  Interaction(Stage& stage, Camera& camera, const ViewerOptions& options);

  void press(double x, double y, int button, const WindowSize& window);
  void move(double x, double y, const WindowSize& window);
  void release();
  void scroll(double dy);

  /// Direct mode swaps the simulation for handles; leaving it gives the simulation back.
  void set_direct(bool on);
  bool direct() const { return direct_; }
  bool dragging() const { return drag_ != Drag::None; }
  /// Removes the poke spring from the simulation.
  void release_poke();
  /// Restarts the pipeline at frame 0 (without a poke).
  void reset();

  const Poke& poke() const { return poke_; }
  const std::vector<int>& handles() const { return handles_; }
  const Eigen::MatrixXd& handle_targets() const { return handle_targets_; }  ///< one row a handle, d columns

  /// The ImGui panel's rectangle: presses there are not picks.
  Eigen::Vector2d panel_min = Eigen::Vector2d::Zero(), panel_max = Eigen::Vector2d::Zero();

 private:
  enum class Drag { None, Orbit, Pan, Poke, Handle };

  int view_at(double x, const WindowSize& window) const;
  Ray ray_at(double x, double y, int view, const WindowSize& window) const;
  /// The control vertex drawn within 12 pixels of (x, y) in `view`, else -1.
  int nearest_control_vertex(double x, double y, int view, const WindowSize& window) const;
  bool remove_handle(int vertex);
  bool grab_handle(int vertex);
  bool start_poke(double x, double y, int view, const WindowSize& window);
  void use_handles();  ///< the driver following the handles (given positions without any)

  Stage& stage_;
  Camera& camera_;
  const ViewerOptions& opt_;
  Drag drag_ = Drag::None;
  double last_x_ = 0, last_y_ = 0;
  int view_of_drag_ = 0;
  Poke poke_;
  bool direct_ = false;
  std::vector<int> handles_;
  Eigen::MatrixXd handle_targets_;
  int dragged_handle_ = -1;
  std::unique_ptr<pipeline::Driver> saved_driver_;  ///< the simulation while in direct mode
};

}  // namespace mbi::viewer
