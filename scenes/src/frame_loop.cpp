#include "frame_loop.hpp"

#include <optional>

namespace mbi::scenes {

void record_failure(RunResult& res, const std::string& what) {
  if (res.failed) return;
  res.failed = true;
  res.message = what;
}

namespace {
// Runs `undo` when it goes, unless keep() was called: the parts of a frame already written are
// taken back when a later part fails.
class Undo {
 public:
  explicit Undo(std::function<void()> undo) : undo_(std::move(undo)) {}
  ~Undo() {
    if (!undo_) return;
    try {
      undo_();
    } catch (const std::exception&) {  // the failure that made us undo is the one reported
    }
  }
  Undo(const Undo&) = delete;
  Undo& operator=(const Undo&) = delete;
  void keep() { undo_ = nullptr; }

 private:
  std::function<void()> undo_;
};
}  // namespace

void FrameLoop::run(RunResult& res, const std::function<void(int, int)>& progress,
                    const std::atomic<int>* stop) {
  const int frames = sc_.simulation.frames;
  for (int f = 0; f <= frames && !res.failed; ++f) {
    // a stop asked for before this frame makes it the last: written whole, as with --frames f
    const int signal = stop ? stop->load() : 0;
    try {
      if (!frame(f, res, signal != 0)) break;
      if (progress) progress(f, frames);
    } catch (const std::exception& e) {
      record_failure(res, "frame " + std::to_string(f) + ": " + e.what());
    }
    if (signal != 0 && !res.failed && f < frames) {
      res.interrupted = signal;
      break;
    }
  }
}

bool FrameLoop::frame(int f, RunResult& res, bool stopping) {
  const pipeline::FrameResult r = pipe_.step();
  if (!r.ok) {
    record_failure(res, r.message);
    return false;
  }
  nlohmann::json record = metrics_.start_frame(f);
  if (pinned_ && !pinned_->step(false).ok) throw Error("the boundary-pinned comparison failed");
  const bool last = f == sc_.simulation.frames || stopping;
  const bool write_now = last || out_.due(f, sc_.simulation.frames);
  std::vector<const Eigen::MatrixXd*> shown;
  std::optional<std::vector<interp::BezierPoints>> picture;
  if (write_now && sc_.output.image) {
    if (pipe_.dim() == 3)
      picture = panels_3d();
    else
      shown = panels_2d();
  }
  metrics_.add_timings(record, f);
  // numbers stay numbers: positions or energies that overflow fail this step (exit 3, what
  // was reached is kept), before anything of this frame is written
  if (!pipe_.positions().allFinite() || !pipe_.control_positions().allFinite())
    throw Error("the positions overflow (not finite)");
  std::optional<interp::DiscontinuityTable> table;
  if (sc_.output.metrics || last) table = metrics_.add_discontinuity(record);
  const Eigen::MatrixXd* normals = write_now && pipe_.options().normals ? &pipe_.normals() : nullptr;
  // all parts of the frame, or none: each is taken back if a later one fails
  const bool drawn = picture.has_value();
  if (drawn) pictures_.add(f, pipe_, *picture);
  Undo undo_picture(drawn ? [this] { pictures_.discard_last(); } : std::function<void()>());
  metrics_.add_frame(std::move(record));
  Undo undo_metrics([this] { metrics_.discard_last(); });
  out_.frame(f, pipe_.control_positions(), pipe_.positions(), shown, write_now, normals);
  undo_picture.keep();
  undo_metrics.keep();
  if (table) res.last_table = *table;
  res.frames = f;
  return true;
}

std::vector<const Eigen::MatrixXd*> FrameLoop::panels_2d() {
  // the run's method is evaluated already, the others only here
  const std::vector<pipeline::Method> methods = picture_methods(pipe_.method());
  std::vector<const Eigen::MatrixXd*> shown;
  others_.resize(methods.size());
  for (size_t k = 0; k < methods.size(); ++k) {
    if (methods[k] == pipe_.method()) {
      shown.push_back(&pipe_.positions());
    } else {
      pipe_.evaluate_with(methods[k], others_[k]);
      shown.push_back(&others_[k]);
    }
  }
  if (pinned_) shown.push_back(&pinned_->positions());
  return shown;
}

std::vector<interp::BezierPoints> FrameLoop::panels_3d() {
  std::vector<interp::BezierPoints> panels;
  for (pipeline::Method k : picture_methods(pipe_.method())) panels.push_back(pipe_.bezier_with(k));
  return panels;
}

}  // namespace mbi::scenes
