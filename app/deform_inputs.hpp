#pragma once
// What mbi deform works on: the rest control mesh and the dense models (Model), and the control
// positions of each frame (Frames): one positions file, a whole trajectory, or the built-in
// example's pose. One pose is a trajectory of one frame; the rest of the command does not ask
// which.
#include "deform_parts.hpp"

#include <mbi/io/io.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace mbi::cli {

struct Model {
  Eigen::MatrixXd U;           ///< rest control positions, n x d
  Eigen::MatrixXi T;           ///< m x (d+1)
  DenseParts dense;            ///< the dense models, their rows in P
  Eigen::MatrixXd P, P_extra;  ///< dense rest points p x d, and columns beyond d (kept as they are)
  std::string control_name, mesh_name;
  /// The deformation in closed form at the dense points (the example only): p x d and (p d) x d.
  Eigen::MatrixXd exact, exact_gradients;
  int dim() const { return static_cast<int>(U.cols()); }
};

/// Reads the control mesh (its notes on stderr) and every --mesh. Throws naming the file.
Model load_model(const std::string& control, const std::vector<std::string>& meshes);
/// The built-in example `name` (twist-bar), its exact solution included.
Model example_model(const std::string& name);
/// The example's deformed control positions (its one frame).
Eigen::MatrixXd example_pose(const std::string& name);

/// The control positions frame by frame.
class Frames {
 public:
  /// `deformed` read as a trajectory (io::Trajectory) or as one positions file; `displacement`:
  /// the point field added to every frame's positions (none when empty).
  Frames(const std::string& deformed, bool trajectory, const std::string& displacement = "");
  /// One pose given in memory (the example), `name` for messages.
  Frames(Eigen::MatrixXd pose, std::string name);
  bool trajectory() const { return traj_.has_value(); }
  /// Resamples the frames to `fps` a second, from the first frame's time to the last's: frame k
  /// at t0 + k / fps, its positions interpolated linearly between the input frames around that
  /// time. Throws naming --fps when the input has no frame times in seconds (only an MDD and a
  /// .pvd have them) or they do not increase.
  void resample(double fps);
  /// The frames' times (s) once resampled; empty otherwise.
  const std::vector<double>& times() const { return times_; }
  io::Trajectory* trajectory_file() { return traj_ ? &*traj_ : nullptr; }
  int count() const;
  /// Frame k as the deformer takes it (n x d), checked against `m`; throws naming the frame.
  /// Without a displacement, warns once for a frame at the rest positions whose file has a
  /// nonzero vector point field of the right size (FEniCS's and deal.II's displacement).
  Eigen::MatrixXd pose(int k, const Model& m);
  /// Where frame k comes from, for messages.
  std::string where(int k) const;
  const std::string& name() const { return name_; }
  /// Every file it reads (never an output).
  std::vector<std::filesystem::path> files() const;

 private:
  void warn_rest(int k, const Eigen::MatrixXd& X, const Model& m);
  Eigen::MatrixXd input_pose(int i, const Model& m);    // input frame i, checked
  Eigen::MatrixXd cached_input(int i, const Model& m);  // the same, the last one kept

  std::string name_, displacement_;
  bool warned_ = false;
  std::optional<io::Trajectory> traj_;
  std::optional<Eigen::MatrixXd> pose_;  // one pose, kept once read
  std::vector<double> times_, input_times_;  // resampled: the output's and the input's frame times
  int cached_ = -1;                          // resampled: the input frame held in cached_pose_
  Eigen::MatrixXd cached_pose_;
};

/// The example's name, or whether `deformed` and the outputs ask for a trajectory: `deformed`
/// names one (io::Trajectory) or an output is a point cache (.pc2, .mdd) or numbered files.
bool is_sequence(const std::string& deformed, const std::vector<std::string>& outs);

}  // namespace mbi::cli
