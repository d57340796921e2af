#pragma once
// Drivers produce the control positions X (n x d) of each frame for the frame pipeline:
//   SimulatorDriver  co-rotational FEM (mbi::sim), with scripted pokes and forces
//   HandleDriver     handles dragged without physics (paper Eq. 10/11, docs/method.md fact 10);
//                    the free positions and M are solved together
//   GivenDriver      positions given from outside: a recorded sequence, or set() each frame by
//                    an external simulator (what `mbi deform` uses)
// Frame 0 is the initial pose: a simulator does not step for it.
#include <mbi/interp/control.hpp>
#include <mbi/pipeline/surface_contact.hpp>
#include <mbi/sim/simulator.hpp>

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace mbi::pipeline {

/// The outcome of driving one frame. A failed drive (a simulation step that blew up, positions
/// missing for a frame) leaves X at the last good frame; `message` says why.
struct DriveResult {
  bool ok = true;
  std::string message;
};

class Driver {
 public:
  virtual ~Driver() = default;
  /// Writes the control positions of `frame` (0, 1, 2, ... in order) into X (n x d).
  virtual DriveResult drive(int frame, Eigen::MatrixXd& X) = 0;
  /// The modified-BI matrices at the X just driven, when the driver solves them jointly with X
  /// (HandleDriver); nullptr otherwise, and the pipeline solves M itself.
  virtual const interp::VertexMatrices* solved_M() const { return nullptr; }
  /// Back to the initial pose (frame 0 comes next).
  virtual void reset() = 0;
  /// "simulation", "handles", "given".
  virtual const char* name() const = 0;
};

/// Co-rotational FEM. Scripted pokes are active on frames [first, last] (first >= 0; a poke
/// with first = 0 acts from the first step on). Contact at the dense surface (set_contact) is
/// the simulator's potential; the ground plane of the simulator's parameters is the contact at
/// the control nodes.
class SimulatorDriver final : public Driver {
 public:
  explicit SimulatorDriver(sim::Simulator simulator);

  /// Constant force (N) at a material point (element, barycentric coordinates) on [first, last].
  void add_scripted_force(int first, int last, int element, const Eigen::Vector4d& bary,
                          const Eigen::Vector3d& force);
  /// Zero-length spring (N/m) pulling a material point toward `target` (m) on [first, last].
  void add_scripted_spring(int first, int last, int element, const Eigen::Vector4d& bary,
                           const Eigen::Vector3d& target, double stiffness);

  /// Contact of embedded points with colliders (method.md fact 16), the simulator's potential
  /// from the next step on; nullptr removes it. Throws as Simulator::set_potential.
  void set_contact(std::shared_ptr<SurfaceContact> contact);
  const std::shared_ptr<SurfaceContact>& contact() const { return contact_; }
  /// Contact points inside a collider at the last frame driven (0 without contact).
  int touching_points() const { return touching_; }

  DriveResult drive(int frame, Eigen::MatrixXd& X) override;
  void reset() override;
  const char* name() const override { return "simulation"; }

  sim::Simulator& simulator() { return sim_; }
  const sim::Simulator& simulator() const { return sim_; }
  /// The last step's result (iterations, times); default before the first step.
  const sim::StepResult& last_step() const { return last_; }

 private:
  struct Scripted {
    int first = 0, last = 0, element = 0;
    Eigen::Vector4d bary = Eigen::Vector4d::Zero();
    bool is_force = true;
    Eigen::Vector3d value = Eigen::Vector3d::Zero();  // force (N) or target (m)
    double stiffness = 0.0;
    int handle = -1;  // simulator handle while active
  };
  void add_scripted(const Scripted& s);
  sim::Simulator sim_;
  std::vector<Scripted> scripted_;
  sim::StepResult last_;
  std::shared_ptr<SurfaceContact> contact_;
  int touching_ = 0;
};

/// Handles dragged without physics (Eq. 10 hard, Eq. 11 soft). Targets (handles x d) come from
/// `targets(frame)` when given, else from the last set_targets() (the rest positions at first).
class HandleDriver final : public Driver {
 public:
  using TargetFunction = std::function<Eigen::MatrixXd(int frame)>;
  HandleDriver(const Eigen::Ref<const Eigen::MatrixXd>& U,
               const Eigen::Ref<const Eigen::MatrixXi>& T, std::vector<int> handles,
               const interp::ControlOptions& options, TargetFunction targets = {});

  void set_targets(const Eigen::Ref<const Eigen::MatrixXd>& targets);
  const std::vector<int>& handles() const { return solver_.handles(); }
  const interp::HandleSolver& solver() const { return solver_; }

  DriveResult drive(int frame, Eigen::MatrixXd& X) override;
  const interp::VertexMatrices* solved_M() const override { return &solver_.last_M(); }
  void reset() override;
  const char* name() const override { return "handles"; }

 private:
  interp::HandleSolver solver_;
  TargetFunction function_;
  Eigen::MatrixXd rest_, targets_, previous_;
};

/// Positions from outside. With a sequence, frame k uses sequence[k] (a frame past its end
/// fails); without one, every frame uses the positions of the last set().
class GivenDriver final : public Driver {
 public:
  /// Starts at the rest pose U; set() replaces it.
  explicit GivenDriver(const Eigen::Ref<const Eigen::MatrixXd>& U);
  explicit GivenDriver(std::vector<Eigen::MatrixXd> sequence);

  void set(const Eigen::Ref<const Eigen::MatrixXd>& X);
  DriveResult drive(int frame, Eigen::MatrixXd& X) override;
  void reset() override {}
  const char* name() const override { return "given"; }

 private:
  std::vector<Eigen::MatrixXd> sequence_;
  Eigen::MatrixXd current_;
};

}  // namespace mbi::pipeline
