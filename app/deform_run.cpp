// mbi deform from the arguments to the exit code: inputs, outputs checked, one embedding and
// precompute, the frames, the comparison and the statistics (deform.hpp).
#include "commands.hpp"
#include "deform.hpp"
#include "deform_outputs.hpp"
#include "signals.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/error.hpp>
#include <mbi/interp.hpp>
#include <mbi/scenes/limits.hpp>

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <new>
#include <stdexcept>

namespace fs = std::filesystem;

namespace mbi::cli {
namespace {

// The interpolation's options from the command's: one place for the estimate and the precompute.
interp::Options interp_options(const DeformArgs& a) {
  interp::Options o;
  o.alpha = a.alpha;
  o.pin_boundary = a.pin_boundary;
  o.max_memory = a.max_memory;
  return o;
}

// SIGINT and SIGTERM while the frames run: the loop stops after the frame in progress (the one
// signal policy of every command, signals.hpp); a second signal ends the process at once.
class StopOnSignal {
 public:
  StopOnSignal() { handle_interrupts(&stop_); }
  ~StopOnSignal() { handle_interrupts(nullptr); }
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;
  int signal() const { return stop_.load(); }

 private:
  std::atomic<int> stop_{0};
};

class Progress {
 public:
  explicit Progress(int total) : total_(total), tty_(total > 1 && isatty(fileno(stderr)) != 0) {}
  void show(int done) {
    if (!tty_) return;
    const int w = 30, filled = w * done / total_;
    std::fprintf(stderr, "\r[%s%s] %3d%%  frame %d/%d  %.1f s", std::string(filled, '#').c_str(),
                 std::string(w - filled, ' ').c_str(), 100 * done / total_, done, total_, ms_since(t0_) / 1000);
    if (done == total_) std::fprintf(stderr, "\n");
  }
  void end(int done) {
    if (tty_ && done != total_) std::fprintf(stderr, "\n");
  }

 private:
  int total_;
  bool tty_;
  Clock::time_point t0_ = Clock::now();
};

// A stage's std::bad_alloc as an error that names the stage: the estimate was passed, but the
// memory went (another program took it, or the estimate missed; docs/performance.md, "Memory").
template <class F>
auto in_stage(const char* stage, F&& f) {
  try {
    return f();
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(std::string("out of memory while ") + stage +
                             " (see the estimate in docs/performance.md, \"Memory\"; --max-memory sets the limit)");
  }
}

void check_args(const DeformArgs& a) {
  if (a.alpha) check_option("--alpha", [&] { interp::check_alpha(*a.alpha); });
  if (a.max_outside) check_option("--max-outside", [&] { interp::check_max_outside(*a.max_outside); });
  if (!a.example.empty()) {
    if (a.outs.size() > 1) throw std::runtime_error("--example writes one --out");
    if (!a.displacement.empty()) throw std::runtime_error("--displacement: --example has no --deformed files");
    return;
  }
  for (const auto& [flag, v] : {std::pair{"--control", &a.control}, {"--deformed", &a.deformed}})
    if (v->empty()) throw std::runtime_error(std::string(flag) + " is required (or use --example)");
  if (a.meshes.empty()) throw std::runtime_error("--mesh is required (or use --example)");
  if (a.outs.empty()) throw std::runtime_error("--out is required (or use --example)");
  if (a.outs.size() != a.meshes.size())
    throw std::runtime_error(std::to_string(a.meshes.size()) + " --mesh but " + std::to_string(a.outs.size()) +
                             " --out: give one --out for each --mesh, in the same order");
}

std::vector<fs::path> input_files(const DeformArgs& a, const Frames& frames) {
  if (!a.example.empty()) return {};
  std::vector<fs::path> inputs = frames.files();
  inputs.insert(inputs.end(), a.meshes.begin(), a.meshes.end());
  for (const fs::path& p : io::control_mesh_files(a.control)) inputs.push_back(p);
  return inputs;
}

// The dense points in the control mesh (a warning for points outside it, --max-outside).
interp::Embedding embed_points(const DeformArgs& a, const Model& m, Run& run) {
  const auto t0 = Clock::now();
  interp::Embedding emb;
  try {
    emb = interp::embed(m.U, m.T, m.P);
  } catch (const mbi::Error& e) {
    throw std::runtime_error(m.mesh_name + ": " + e.what());
  }
  run.embed_ms = ms_since(t0);
  if (!emb.outside.empty()) std::fprintf(stderr, "mbi deform: warning: %s\n", interp::outside_message(emb).c_str());
  if (a.max_outside) {
    const interp::FarPoints far = interp::far_points(emb, m.P, *a.max_outside);
    if (far.count > 0)
      throw std::runtime_error(m.mesh_name + ": " + interp::far_points_message(far, "--max-outside ", m.control_name));
  }
  return emb;
}

// The embedding and the method's precompute, timed into `run`; with rest normals when `normals`.
pipeline::Deformer make_deformer(const DeformArgs& a, const Model& m, bool normals, Run& run) {
  interp::Embedding emb = embed_points(a, m, run);
  test_signal_at("precompute");
  // One element has no interior face: BI and Phong need none; modified-BI minimises the
  // discontinuity across interior faces and needs at least one.
  if (a.method == pipeline::Method::ModifiedBI && interp::interior_faces(m.T).rows() == 0)
    throw std::runtime_error(m.control_name + ": the control mesh has no interior face (one element); "
                             "modified-BI minimises the discontinuity across interior faces and needs at "
                             "least two face-adjacent elements (--method bi or phong take it)");
  const pipeline::DeformerOptions opt{.method = a.method, .interp = interp_options(a)};
  const auto t0 = Clock::now();
  try {
    pipeline::Deformer deformer(m.U, m.T, std::move(emb), opt, normals ? m.dense.normals() : Eigen::MatrixXd());
    run.precompute_ms = ms_since(t0);
    return deformer;
  } catch (const mbi::Error& e) {
    throw std::runtime_error(m.control_name + ": " + e.what());
  }
}

// The outputs' needs: deformed normals (surfaces and glTF of a part with normals; caches hold
// positions only) and the float kernel (a 3D model into caches only: its output is their layout).
struct Needs {
  bool normals = false, use_float = false;
};

Needs output_needs(const std::vector<Out>& outs, const Model& m) {
  Needs n{.normals = false, .use_float = m.dim() == 3 && m.P_extra.cols() == 0};
  for (const Out& o : outs) {
    n.normals |= o.kind == OutKind::gltf || (o.kind != OutKind::pc2 && o.kind != OutKind::mdd && io::is_surface_file(o.name));
    n.use_float &= o.kind == OutKind::pc2 || o.kind == OutKind::mdd;
  }
  n.normals = n.normals && m.dim() == 3 && m.dense.normals().rows() > 0;
  return n;
}

// Frame k: read, deformed, written; its time into `run`.
void run_frame(int k, Frames& frames, const Model& m, pipeline::Deformer& deformer, FrameWriter& out, Run& run,
               Eigen::MatrixXd& positions, Eigen::MatrixXd& normals, interp::RowMatrixXf& xyz) {
  auto t0 = Clock::now();
  run.last_pose = frames.pose(k, m);
  run.read_ms += ms_since(t0);
  t0 = Clock::now();
  const Eigen::MatrixXd& X = run.last_pose;
  if (xyz.size() > 0) deformer.deform_float(X, xyz);
  else if (normals.size() > 0) deformer.deform(X, positions, normals);
  else deformer.deform(X, positions);
  if (xyz.size() == 0 && !positions.allFinite()) throw std::runtime_error("evaluation produced non-finite positions");
  run.deform_ms += ms_since(t0);
  t0 = Clock::now();
  if (xyz.size() > 0) out.write(xyz);
  else out.write(k, positions, normals);
  run.write_ms += ms_since(t0);
}

void run_frames(Frames& frames, const Model& m, pipeline::Deformer& deformer, FrameWriter& out, bool use_float,
                const StopOnSignal& stop, const io::OutputSet& outputs, Run& run) {
  Progress progress(frames.count());
  Eigen::MatrixXd positions(m.P.rows(), m.dim()), normals;
  if (deformer.has_rest_normals()) normals.resize(m.P.rows(), 3);
  interp::RowMatrixXf xyz(use_float ? m.P.rows() : 0, 3);
  const int signal_frame = std::min(1, frames.count() - 1);  // the test hook: the second frame, or the one
  for (int k = 0; k < frames.count() && !(run.signal = stop.signal()); ++k) {
    try {
      if (k == signal_frame) test_signal_at("frame");
      run_frame(k, frames, m, deformer, out, run, positions, normals, xyz);
    } catch (const std::exception& e) {
      const bool oom = dynamic_cast<const std::bad_alloc*>(&e) != nullptr;  // named, not "std::bad_alloc"
      const std::string what = outputs.name_targets(oom ? "out of memory while deforming the frame" : e.what()),
                        frame = "frame " + std::to_string(k);
      run.failure = !run.trajectory || what.find(frame) != std::string::npos ? what : frame + ": " + what;
      break;
    }
    run.done = k + 1;
    progress.show(run.done);
  }
  progress.end(run.done);
}

// Exit code and message of a run that stopped early; 0 when it did not.
int report_stop(const Run& run) {
  if (!run.failure.empty()) {
    std::fprintf(stderr, "mbi deform: error: %s (outputs up to frame %d kept)\n", run.failure.c_str(), run.done - 1);
    return 3;
  }
  if (run.signal) {
    std::fprintf(stderr, "mbi deform: interrupted by %s (outputs up to frame %d kept%s)\n",
                 run.signal == SIGINT ? "SIGINT" : "SIGTERM", run.done - 1,
                 run.done == run.frames ? ": every frame was done, the outputs are finished" : "");
    return 128 + run.signal;
  }
  return 0;
}

// The comparison of the last frame; a trajectory whose frames are written keeps them when it
// fails (a warning), one pose fails with it.
std::optional<Comparison> try_compare(const Model& m, const pipeline::Deformer& deformer, Run& run) {
  try {
    return compare_methods(m, deformer, run);
  } catch (const std::exception& e) {
    if (!run.trajectory) throw;
    std::fprintf(stderr, "mbi deform: warning: no discontinuity table for the last frame: %s\n", e.what());
    return std::nullopt;
  }
}

// Everything from the models to the last rename; `outputs` holds every output but numbered files.
int deform_frames(const DeformArgs& a, Frames& frames, const std::vector<Out>& outs, io::OutputSet& outputs,
                  std::size_t i_stats) {
  test_signal_at("load");
  const Model m = in_stage("reading the models", [&] {
    return a.example.empty() ? load_model(a.control, a.meshes) : example_model(a.example);
  });
  // the estimate against the memory there is, before the embedding and the precompute allocate
  // (docs/limits.md)
  const auto t_estimate = Clock::now();
  const interp::MemoryEstimate estimate = in_stage("estimating the memory", [&] {
    return scenes::check_run_size(m.control_name, m.P.rows(), m.U, m.T, interp_options(a));
  });
  const double estimate_ms = ms_since(t_estimate);
  if (frames.count() == 0) throw std::runtime_error(a.deformed + ": no frames");
  frames.pose(0, m);  // a wrong node count fails before any work
  const Needs needs = output_needs(outs, m);
  Run run;
  run.frames = frames.count();
  run.trajectory = frames.trajectory();
  run.estimate = estimate;
  run.estimate_ms = estimate_ms;
  const Timing timing = output_timing(frames, a.fps, outs);
  pipeline::Deformer deformer = in_stage("embedding the points and the precompute", [&] { return make_deformer(a, m, needs.normals, run); });
  // From the first frame to the last rename a signal stops the frames, and what was done is
  // finished (signals.hpp); before, it ends the process at once with nothing written.
  const StopOnSignal stop;
  std::optional<Comparison> comparison;
  try {
    FrameWriter out(outs, outputs, m, timing);
    in_stage("deforming the frames", [&] {
      run_frames(frames, m, deformer, out, needs.use_float, stop, outputs, run);
      return 0;
    });
    if (run.done == 0 && run.signal) {
      std::fprintf(stderr, "mbi deform: interrupted by %s before the first frame: nothing written\n",
                   run.signal == SIGINT ? "SIGINT" : "SIGTERM");
      return 128 + run.signal;
    }
    if (run.done == 0) throw std::runtime_error(run.failure);
    comparison = in_stage("comparing the methods", [&] { return try_compare(m, deformer, run); });
    test_signal_at("finish");
    out.finish();
  } catch (const std::exception& e) {
    throw std::runtime_error(outputs.name_targets(e.what()));
  }
  if (!a.stats.empty()) {
    if (!run.signal) run.signal = stop.signal();
    const nlohmann::json j = stats_json(a, m, deformer, run, comparison);
    check_finite(j, a.stats);
    outputs.write(i_stats, [&](const fs::path& p) { io::write_text_atomic(p, j.dump(2) + "\n"); });
  }
  outputs.commit();
  if (!run.signal) run.signal = stop.signal();
  print_summary(a, m, deformer, run, comparison);
  if (!run.trajectory && run.failure.empty())
    for (const std::string& o : a.outs) std::printf("wrote %s\n", o.c_str());
  return report_stop(run);
}

}  // namespace

int run_deform(const DeformArgs& a) {
  check_args(a);
  const bool example = !a.example.empty(), trajectory = !example && is_sequence(a.deformed, a.outs);
  std::vector<Out> outs = output_kinds(a.outs, trajectory);
  Frames frames = example ? Frames(example_pose(a.example), "built-in twist (90 degrees, mild bend)")
                          : Frames(a.deformed, trajectory, a.displacement);
  if (a.fps) {
    check_fps(*a.fps, frames.count());
    frames.resample(*a.fps);
  }
  // One overwrite rule (docs/cli.md): every output checked before any work, inputs never outputs.
  const std::vector<fs::path> inputs = input_files(a, frames);
  io::OutputSet outputs(inputs, a.force);
  reserve_outputs(outs, outputs);
  const std::size_t i_stats = a.stats.empty() ? 0 : outputs.add(a.stats, "--stats");
  check_outputs(outs, a.stats, inputs, a.force, frames.count());
  return deform_frames(a, frames, outs, outputs, i_stats);
}

}  // namespace mbi::cli
