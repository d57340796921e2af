#include <mbi/error.hpp>
#include <mbi/interp/parallel.hpp>
#include <mbi/pipeline/contact_setup.hpp>
#include <mbi/pipeline/driver.hpp>

namespace mbi::pipeline {

// ------------------------------------------------------------------------------ SimulatorDriver

SimulatorDriver::SimulatorDriver(sim::Simulator simulator) : sim_(std::move(simulator)) {
  // the simulator's element and node loops on the library's threads (its results do not change)
  sim_.set_parallel_for([](long long count, long long block, const std::function<void(long long, long long)>& f) {
    interp::parallel_for(count, block, f);
  });
}

void SimulatorDriver::add_scripted(const Scripted& s) {
  if (s.first < 0 || s.last < s.first)
    throw Error(std::string(s.is_force ? "scripted force" : "scripted poke") + ": frames [" +
                std::to_string(s.first) + ", " + std::to_string(s.last) + "] are not a range of frames >= 0");
  scripted_.push_back(s);
}

void SimulatorDriver::add_scripted_force(int first, int last, int element,
                                         const Eigen::Vector4d& bary,
                                         const Eigen::Vector3d& force) {
  add_scripted({first, last, element, bary, true, force, 0.0, -1});
}

void SimulatorDriver::add_scripted_spring(int first, int last, int element,
                                          const Eigen::Vector4d& bary,
                                          const Eigen::Vector3d& target, double stiffness) {
  add_scripted({first, last, element, bary, false, target, stiffness, -1});
}

void SimulatorDriver::set_contact(std::shared_ptr<SurfaceContact> contact) {
  sim_.set_potential(contact);
  contact_ = std::move(contact);
  touching_ = 0;
}

DriveResult SimulatorDriver::drive(int frame, Eigen::MatrixXd& X) {
  if (frame > 0) {
    // A scripted poke acts on the steps that produce frames first..last.
    for (Scripted& s : scripted_) {
      const bool active = frame >= s.first && frame <= s.last;
      if (active && s.handle < 0)
        s.handle = s.is_force ? sim_.add_point_force(s.element, s.bary, s.value)
                              : sim_.add_poke(s.element, s.bary, s.value, s.stiffness);
      if (!active && s.handle >= 0) {
        sim_.remove(s.handle);
        s.handle = -1;
      }
    }
    last_ = sim_.step();
    if (!last_.success) return {false, last_.message};
  }
  X = sim_.positions();
  if (contact_) {
    if (frame == 0) contact_->set_time(sim_.time());  // the initial pose: the colliders then
    touching_ = pipeline::touching_points(*contact_, X);
  }
  return {};
}

void SimulatorDriver::reset() {
  for (Scripted& s : scripted_)
    if (s.handle >= 0) {
      sim_.remove(s.handle);
      s.handle = -1;
    }
  sim_.reset();
  last_ = {};
  touching_ = 0;
}

// ------------------------------------------------------------------------------ HandleDriver

HandleDriver::HandleDriver(const Eigen::Ref<const Eigen::MatrixXd>& U,
                           const Eigen::Ref<const Eigen::MatrixXi>& T, std::vector<int> handles,
                           const interp::ControlOptions& options, TargetFunction targets)
    : solver_(U, T, std::move(handles), options), function_(std::move(targets)), rest_(U) {
  targets_.resize(static_cast<Eigen::Index>(solver_.handles().size()), U.cols());
  for (size_t k = 0; k < solver_.handles().size(); ++k)
    targets_.row(static_cast<Eigen::Index>(k)) = U.row(solver_.handles()[k]);
  previous_ = rest_;
}

void HandleDriver::set_targets(const Eigen::Ref<const Eigen::MatrixXd>& targets) {
  if (targets.rows() != targets_.rows() || targets.cols() != targets_.cols())
    throw Error("handle targets must be " + std::to_string(targets_.rows()) + " x " +
                std::to_string(targets_.cols()) + ", got " + std::to_string(targets.rows()) +
                " x " + std::to_string(targets.cols()));
  if (!targets.allFinite()) throw Error("handle targets: non-finite position");
  targets_ = targets;
}

DriveResult HandleDriver::drive(int frame, Eigen::MatrixXd& X) {
  if (function_) set_targets(function_(frame));
  previous_ = solver_.solve(targets_, previous_);
  X = previous_;
  return {};
}

void HandleDriver::reset() { previous_ = rest_; }

// ------------------------------------------------------------------------------ GivenDriver

GivenDriver::GivenDriver(const Eigen::Ref<const Eigen::MatrixXd>& U) : current_(U) {}

GivenDriver::GivenDriver(std::vector<Eigen::MatrixXd> sequence) : sequence_(std::move(sequence)) {
  if (sequence_.empty()) throw Error("the sequence of positions is empty");
  for (size_t k = 0; k < sequence_.size(); ++k)
    if (sequence_[k].rows() != sequence_[0].rows() || sequence_[k].cols() != sequence_[0].cols())
      throw Error("frame " + std::to_string(k) + " has " +
                  std::to_string(sequence_[k].rows()) + " x " + std::to_string(sequence_[k].cols()) +
                  " positions, frame 0 has " + std::to_string(sequence_[0].rows()) + " x " +
                  std::to_string(sequence_[0].cols()));
}

void GivenDriver::set(const Eigen::Ref<const Eigen::MatrixXd>& X) {
  if (!sequence_.empty()) throw Error("set() on a driver that plays a sequence");
  current_ = X;
}

DriveResult GivenDriver::drive(int frame, Eigen::MatrixXd& X) {
  if (sequence_.empty()) {
    X = current_;
    return {};
  }
  if (frame < 0 || frame >= static_cast<int>(sequence_.size()))
    return {false, "no control positions for frame " + std::to_string(frame) + " (the sequence has " +
                       std::to_string(sequence_.size()) + ")"};
  X = sequence_[static_cast<size_t>(frame)];
  return {};
}

}  // namespace mbi::pipeline
