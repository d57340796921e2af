// mbi deform's inputs (deform_inputs.hpp).
#include "deform_inputs.hpp"

#include <mbi/generate/procedural.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace mbi::cli {

Model load_model(const std::string& control, const std::vector<std::string>& meshes) {
  Model m;
  m.control_name = control;
  io::ControlMesh cm = io::read_control_mesh(control);
  for (const std::string& note : cm.notes) std::fprintf(stderr, "mbi deform: note: %s\n", note.c_str());
  m.U = std::move(cm.U);
  m.T = std::move(cm.T);
  m.dense = read_dense_parts(meshes);
  m.mesh_name = m.dense.names();
  const Eigen::MatrixXd& P = m.dense.P;
  const int d = m.dim();
  if (P.cols() < d)
    throw std::runtime_error(m.mesh_name + ": points have " + std::to_string(P.cols()) +
                             " coordinates, the control mesh is " + std::to_string(d) + "D");
  m.P = P.leftCols(d);
  m.P_extra = P.rightCols(P.cols() - d);
  return m;
}

namespace {

void check_example(const std::string& name) {
  if (name != "twist-bar") throw std::runtime_error("--example: unknown example \"" + name + "\" (known: twist-bar)");
}

}  // namespace

Eigen::MatrixXd example_pose(const std::string& name) {
  check_example(name);
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  generate::paper_bar_control(U, T);
  return generate::twist_bend(U, 0.0, 0.0, 0.0, 6.0, std::acos(-1.0) / 2, 0.05);
}

Model example_model(const std::string& name) {
  check_example(name);
  Model m;
  m.control_name = "built-in paper bar (35 vertices)";
  m.mesh_name = "built-in bar surface";
  generate::paper_bar_control(m.U, m.T);
  io::SurfaceMesh s;
  generate::paper_bar_surface(s.V, s.F);
  m.P = s.V;
  m.P_extra.resize(s.V.rows(), 0);
  m.dense.parts.push_back({.file = m.mesh_name, .surface = s, .first = 0, .rows = s.V.rows()});
  m.dense.P = s.V;
  const double pi = std::acos(-1.0);
  m.exact = generate::twist_bend(m.P, 0.0, 0.0, 0.0, 6.0, pi / 2, 0.05);
  m.exact_gradients = generate::twist_bend_jacobian(m.P, 0.0, 0.0, 0.0, 6.0, pi / 2, 0.05);
  return m;
}

Frames::Frames(const std::string& deformed, bool trajectory, const std::string& displacement)
    : name_(deformed), displacement_(displacement) {
  if (trajectory) traj_.emplace(deformed, displacement);  // the list of frames; every file named exists
}

Frames::Frames(Eigen::MatrixXd pose, std::string name) : name_(std::move(name)), pose_(std::move(pose)) {}

int Frames::count() const { return !times_.empty() ? static_cast<int>(times_.size()) : traj_ ? traj_->frames() : 1; }

std::string Frames::where(int k) const {
  if (times_.empty()) return traj_ ? traj_->where(k) : name_;
  char t[64];
  std::snprintf(t, sizeof t, " (resampled at %.6g s)", times_.at(static_cast<std::size_t>(k)));
  return name_ + ": frame " + std::to_string(k) + t;
}

void Frames::resample(double fps) {
  if (!traj_ || !traj_->has_times())
    throw std::runtime_error("--fps: " + name_ + " has no frame times in seconds to resample (" +
                             (traj_ && traj_->pc2_timing() ? "a PC2 numbers its frames without a rate; " : "") +
                             "an MDD or a .pvd has them); leave --fps out to keep its frames as they are");
  input_times_ = traj_->times();
  for (std::size_t i = 1; i < input_times_.size(); ++i)
    if (!(input_times_[i] > input_times_[i - 1]))
      throw std::runtime_error("--fps: " + name_ + ": frame times do not increase at frame " + std::to_string(i) +
                               ": nothing to resample between");
  const double t0 = input_times_.front(), span = input_times_.back() - t0;
  const double n = std::floor(span * fps * (1 + 1e-12)) + 1;  // a last time on the grid counts
  constexpr double kMaxFrames = 1 << 24;
  if (!(n <= kMaxFrames))
    throw std::runtime_error("--fps: " + std::to_string(span) + " s at this rate are more than " +
                             std::to_string(static_cast<long>(kMaxFrames)) + " frames");
  times_.clear();
  for (int k = 0; k < static_cast<int>(n); ++k) times_.push_back(std::min(t0 + k / fps, input_times_.back()));
}

// Input frame i, the one last read kept (neighbouring times share it).
Eigen::MatrixXd Frames::cached_input(int i, const Model& m) {
  if (i != cached_) {
    cached_pose_ = input_pose(i, m);
    cached_ = i;
  }
  return cached_pose_;
}

std::vector<std::filesystem::path> Frames::files() const {
  if (traj_) return traj_->files();
  if (pose_) return {};
  return {name_};
}

Eigen::MatrixXd Frames::pose(int k, const Model& m) {
  if (!times_.empty()) {  // linear between the input frames i and i + 1 around the time
    const double t = times_.at(static_cast<std::size_t>(k));
    const auto after = std::upper_bound(input_times_.begin(), input_times_.end(), t);
    const int i = static_cast<int>(std::max<std::ptrdiff_t>(after - input_times_.begin() - 1, 0));
    if (i + 1 >= static_cast<int>(input_times_.size())) return cached_input(i, m);
    const double s = (t - input_times_[static_cast<std::size_t>(i)]) /
                     (input_times_[static_cast<std::size_t>(i + 1)] - input_times_[static_cast<std::size_t>(i)]);
    const Eigen::MatrixXd a = cached_input(i, m);
    if (s == 0) return a;
    const Eigen::MatrixXd b = cached_input(i + 1, m);
    return (1 - s) * a + s * b;
  }
  return input_pose(k, m);
}

Eigen::MatrixXd Frames::input_pose(int k, const Model& m) {
  Eigen::MatrixXd X;
  if (traj_) X = traj_->read(k);
  else if (pose_) X = *pose_;
  else pose_ = X = io::read_positions(name_, displacement_);
  const std::string where = traj_ ? traj_->where(k) : name_, noun = traj_ ? " positions" : " deformed positions";
  const int d = m.dim();
  if (d == 2 && X.cols() == 3) {
    // 2D positions stored with z (a .msh, a .vtk, meshio's 3-column text): one plane, dropped
    if (X.rows() > 0 && (X.col(2).array() != X(0, 2)).any())
      throw std::runtime_error(where + ": the control mesh is 2D but these positions are not in one plane z = const");
    X.conservativeResize(Eigen::NoChange, 2);
  }
  if (X.rows() != m.U.rows())
    throw std::runtime_error(where + ": " + std::to_string(X.rows()) + noun + ", but the control mesh " +
                             m.control_name + " has " + std::to_string(m.U.rows()) + " vertices");
  if (X.cols() != d)
    throw std::runtime_error(where + ": positions have " + std::to_string(X.cols()) + " coordinates, but the control mesh " +
                             m.control_name + " is " + std::to_string(d) + "D");
  if (!X.allFinite()) throw std::runtime_error(where + ": non-finite position");
  if (displacement_.empty() && !warned_) warn_rest(k, X, m);
  return X;
}

void Frames::warn_rest(int k, const Eigen::MatrixXd& X, const Model& m) {
  const std::filesystem::path file = traj_ ? traj_->file(k) : std::filesystem::path(name_);
  const std::string ext = io::lower_extension(file);
  if (ext != ".vtu" && ext != ".vtk") return;
  const double size = std::max(1.0, m.U.cwiseAbs().maxCoeff());
  if ((X - m.U).cwiseAbs().maxCoeff() > 1e-9 * size) return;
  for (const io::PointField& f : io::read_point_data(file).fields)
    if (f.values.rows() == X.rows() && (f.values.cols() == 3 || f.values.cols() == m.dim()) && f.values.allFinite() &&
        f.values.cwiseAbs().maxCoeff() > 0) {
      std::fprintf(stderr,
                   "mbi deform: warning: %s: the positions are the rest mesh's, and the file has a vector point field "
                   "'%s' (%lld x %lld): give --displacement %s to add it to the positions\n",
                   (traj_ ? traj_->where(k) : name_).c_str(), f.name.c_str(), static_cast<long long>(f.values.rows()),
                   static_cast<long long>(f.values.cols()), f.name.c_str());
      warned_ = true;
      return;
    }
}

bool is_sequence(const std::string& deformed, const std::vector<std::string>& outs) {
  if (io::Trajectory::names_trajectory(deformed)) return true;
  for (const std::string& out : outs) {
    const std::string ext = io::lower_extension(out);
    if (ext == ".pc2" || ext == ".mdd" || io::is_numbered_name(out)) return true;
  }
  return false;
}

}  // namespace mbi::cli
