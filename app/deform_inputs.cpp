// mbi deform's inputs (deform_inputs.hpp).
#include "deform_inputs.hpp"

#include <mbi/generate/procedural.hpp>

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

Frames::Frames(const std::string& deformed, bool trajectory) : name_(deformed) {
  if (trajectory) traj_.emplace(deformed);  // the list of frames; every file named exists
}

Frames::Frames(Eigen::MatrixXd pose, std::string name) : name_(std::move(name)), pose_(std::move(pose)) {}

int Frames::count() const { return traj_ ? traj_->frames() : 1; }

std::string Frames::where(int k) const { return traj_ ? traj_->where(k) : name_; }

std::vector<std::filesystem::path> Frames::files() const {
  if (traj_) return traj_->files();
  if (pose_) return {};
  return {name_};
}

Eigen::MatrixXd Frames::pose(int k, const Model& m) {
  Eigen::MatrixXd X;
  if (traj_) X = traj_->read(k);
  else if (pose_) X = *pose_;
  else pose_ = X = io::read_positions(name_);
  const std::string where = this->where(k), noun = traj_ ? " positions" : " deformed positions";
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
  return X;
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
