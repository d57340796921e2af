#pragma once
// The mouse on the model (internal): picking in the view under the cursor, pokes (grab the
// surface, a bounded spring pulls the grabbed material point to the cursor), collider drags
// (grab a collider of surface contact, it follows the cursor and pushes the model), direct mode
// (click control vertices to make them handles and drag them; no physics), orbit, pan and zoom.
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
  /// Before a step of `dt` s (0: no step follows): the grabbed collider is carried to the
  /// cursor's place on its drag plane, at the velocity that gets it there in dt.
  void carry_collider(double dt);
  /// Restarts the pipeline at frame 0 (without a poke).
  void reset();

  const Poke& poke() const { return poke_; }
  /// The collider being dragged (an index into the contact's colliders), else -1.
  int grabbed_collider() const { return drag_ == Drag::Collider ? grabbed_collider_ : -1; }
  /// The grabbed collider's point under the cursor at the press, and where the cursor asks it
  /// to be now (on the plane through the grab facing the camera).
  const Eigen::Vector3d& collider_grab() const { return collider_grab_; }
  const Eigen::Vector3d& collider_target() const { return collider_target_; }
  const std::vector<int>& handles() const { return handles_; }
  const Eigen::MatrixXd& handle_targets() const { return handle_targets_; }  ///< one row a handle, d columns

  /// The ImGui panel's rectangle: presses there are not picks.
  Eigen::Vector2d panel_min = Eigen::Vector2d::Zero(), panel_max = Eigen::Vector2d::Zero();

 private:
  enum class Drag { None, Orbit, Pan, Poke, Handle, Collider };

  int view_at(double x, const WindowSize& window) const;
  Ray ray_at(double x, double y, int view, const WindowSize& window) const;
  /// The control vertex drawn within 12 pixels of (x, y) in `view`, else -1.
  int nearest_control_vertex(double x, double y, int view, const WindowSize& window) const;
  bool remove_handle(int vertex);
  bool grab_handle(int vertex);
  /// A poke or a collider drag, whichever of the model and the colliders the ray meets first.
  bool grab_under(double x, double y, int view, const WindowSize& window);
  void start_poke(const Hit& hit);
  void use_handles();  ///< the driver following the handles (given positions without any)

  Stage& stage_;
  Camera& camera_;
  const ViewerOptions& opt_;
  Drag drag_ = Drag::None;
  double last_x_ = 0, last_y_ = 0;
  int view_of_drag_ = 0;
  Poke poke_;
  int grabbed_collider_ = -1;
  Eigen::Vector3d collider_grab_ = Eigen::Vector3d::Zero(), collider_target_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d collider_carried_ = Eigen::Vector3d::Zero();  ///< where the grab point has been carried
  bool direct_ = false;
  std::vector<int> handles_;
  Eigen::MatrixXd handle_targets_;
  int dragged_handle_ = -1;
  std::unique_ptr<pipeline::Driver> saved_driver_;  ///< the simulation while in direct mode
};

}  // namespace mbi::viewer
