// mbi deform --deformed TRAJECTORY --out CACHE|NUMBERED: a whole animation (deform_sequence.hpp).
#include "deform_sequence.hpp"
#include "signals.hpp"

#include "commands.hpp"
#include "deform_outside.hpp"
#include "deform_parts.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/error.hpp>
#include <mbi/io/atomic_file.hpp>
#include <mbi/io/io.hpp>
#include <mbi/pipeline/deformer.hpp>
#include <mbi/scenes/limits.hpp>

#include <unistd.h>

#include <atomic>
#include <cfloat>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace mbi::cli {
namespace {

enum class OutKind { pc2, mdd, gltf, numbered };

OutKind out_kind(const std::string& out) {
  const std::string ext = io::lower_extension(out);
  if (ext == ".pc2") return OutKind::pc2;
  if (ext == ".mdd") return OutKind::mdd;
  const bool numbered = io::is_numbered_name(out);
  if ((ext == ".glb" || ext == ".gltf") && !numbered) return OutKind::gltf;
  if (!numbered)
    throw std::runtime_error("--out " + out + ": a sequence goes into a point cache (.pc2, .mdd), an animated glTF "
                             "(.glb, .gltf) or numbered files (a printf pattern: out_%04d.obj)");
  const io::FileFormat* f = io::file_format(out);
  if (!f || (f->kind != io::FileKind::surface && f->kind != io::FileKind::points))
    throw std::runtime_error("--out " + out + ": numbered files are .obj, .ply, .off, .stl, .txt or .xyz");
  io::numbered_file(out, 0);  // the pattern is checked here
  return OutKind::numbered;
}

// One --out: its name, kind and index in the command's OutputSet (caches and glTF).
struct Out {
  std::string name;
  OutKind kind;
  std::size_t index = 0;
};

// The rest control mesh and the dense models (their points concatenated: deform_parts.hpp).
struct Model {
  io::ControlMesh control;
  DenseParts dense;
  Eigen::MatrixXd P, P_extra;  // dense rest points p x d, and columns beyond d (kept as they are)
  int dim() const { return control.dim(); }
};

Model load_model(const SequenceArgs& a) {
  Model m;
  m.control = io::read_control_mesh(a.control);
  for (const std::string& note : m.control.notes) std::fprintf(stderr, "mbi deform: note: %s\n", note.c_str());
  m.dense = read_dense_parts(a.meshes);
  const Eigen::MatrixXd& P = m.dense.P;
  const int d = m.dim();
  if (P.cols() < d)
    throw std::runtime_error(m.dense.names() + ": points have " + std::to_string(P.cols()) +
                             " coordinates, the control mesh is " + std::to_string(d) + "D");
  m.P = P.leftCols(d);
  m.P_extra = P.rightCols(P.cols() - d);
  for (const DensePart& part : m.dense.parts)
    if (d + m.P_extra.cols() > 3 && part.surface) throw std::runtime_error(part.file + ": more than 3 coordinates a point");
  return m;
}

// A frame's positions as the deformer takes them (n x d), or an error naming the frame.
Eigen::MatrixXd to_pose(Eigen::MatrixXd X, const Model& m, const std::string& where, const std::string& control) {
  const int d = m.dim();
  if (d == 2 && X.cols() == 3) {  // 2D positions stored with z: one plane, dropped
    if (X.rows() > 0 && (X.col(2).array() != X(0, 2)).any())
      throw std::runtime_error(where + ": the control mesh is 2D but these positions are not in one plane z = const");
    X.conservativeResize(Eigen::NoChange, 2);
  }
  if (X.rows() != m.control.U.rows())
    throw std::runtime_error(where + ": " + std::to_string(X.rows()) + " positions, but the control mesh " + control +
                             " has " + std::to_string(m.control.U.rows()) + " vertices");
  if (X.cols() != d)
    throw std::runtime_error(where + ": positions have " + std::to_string(X.cols()) + " coordinates, but the control mesh " +
                             control + " is " + std::to_string(d) + "D");
  return X;
}

// The output's timing: PC2 start frame and sample rate (frames), MDD and glTF times (s).
struct Timing {
  float pc2_start = 0.0f, pc2_rate = 1.0f;
  std::vector<float> mdd_times;
  std::vector<double> gltf_times;  // strictly increasing, as glTF keys must be
};

std::string short_number(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

// The MDD times when they increase, else one frame every 1/fps seconds.
std::vector<double> increasing_times(const std::vector<float>& times, double fps) {
  std::vector<double> t(times.begin(), times.end());
  for (std::size_t k = 1; k < t.size(); ++k)
    if (!(t[k] > t[k - 1])) {
      for (std::size_t i = 0; i < t.size(); ++i) t[i] = static_cast<double>(i) / fps;
      break;
    }
  return t;
}

Timing cache_timing(const io::Trajectory& t, double fps) {
  Timing o;
  const int F = t.frames();
  const std::vector<double>& times = t.times();
  if (const auto pc2 = t.pc2_timing()) {
    o.pc2_start = pc2->first;
    o.pc2_rate = pc2->second;
    for (int k = 0; k < F; ++k) o.mdd_times.push_back(static_cast<float>((pc2->first + k * pc2->second) / fps));
    return o;
  }
  if (times.empty()) {
    for (int k = 0; k < F; ++k) o.mdd_times.push_back(static_cast<float>(k / fps));
    return o;
  }
  for (double x : times) o.mdd_times.push_back(static_cast<float>(x));
  // evenly spaced times become a PC2's start and rate in frames at fps; others: frame numbers
  const double dt = F > 1 ? (times.back() - times.front()) / (F - 1) : 1.0 / fps;
  bool even = dt > 0;
  for (int k = 0; k < F && even; ++k)
    even = std::abs(times[static_cast<std::size_t>(k)] - (times.front() + k * dt)) <= 1e-6 * std::max(1.0, std::abs(dt * F));
  if (even) {
    o.pc2_start = static_cast<float>(times.front() * fps);
    o.pc2_rate = static_cast<float>(dt * fps);
  }
  return o;
}

// The most frames whose times a sequence holds in memory (MDD and glTF outputs; 12 bytes a
// frame): float32 times cannot increase over more frames evenly spaced anyway.
constexpr int kMaxTimedFrames = 1 << 24;

// The timing of the outputs; the per-frame times only when `per_frame` (an MDD or glTF output).
Timing output_timing(const io::Trajectory& t, double fps, bool per_frame, const std::string& out) {
  if (!per_frame && !t.has_times()) {
    Timing o;
    if (const auto pc2 = t.pc2_timing()) o.pc2_start = pc2->first, o.pc2_rate = pc2->second;
    return o;
  }
  if (t.frames() > kMaxTimedFrames)
    throw std::runtime_error("--out " + out + ": " + std::to_string(t.frames()) + " frames of " + t.spec() +
                             " are more than the " + std::to_string(kMaxTimedFrames) +
                             " frames whose times a sequence holds (write a PC2 from a PC2, or fewer frames)");
  Timing o = cache_timing(t, fps);
  o.gltf_times = increasing_times(o.mdd_times, fps);
  return o;
}

// An --fps whose frame times k / fps (s) are finite and strictly increasing as float32 (MDD and
// glTF store them so) for every frame; `frames` at least 1.
void check_fps(double fps, int frames) {
  const double last = std::max(frames - 1, 1);
  const float dt = static_cast<float>(1.0 / fps), end = static_cast<float>(last / fps);
  if (std::isnormal(dt) && std::isfinite(end)) return;
  char range[96];
  std::snprintf(range, sizeof range, "from %.3g to %.3g", last / static_cast<double>(FLT_MAX), 1.0 / FLT_MIN);
  throw std::runtime_error("--fps " + short_number(fps) + ": the times of " + std::to_string(frames) +
                           " frames at this rate are not finite and increasing as float32; give a rate " + range);
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

// Writes one dense part's frames as they come: into a point cache or an animated glTF (finished
// at the end, or at the last good frame) or one numbered file a frame (each complete when it
// appears).
class PartWriter {
 public:
  PartWriter(OutKind kind, const fs::path& file, const std::string& pattern, const DensePart& part,
             const Eigen::MatrixXd& extra, const Timing& timing)
      : kind_(kind), pattern_(pattern), extra_(extra) {
    const int p = static_cast<int>(part.rows);
    if (kind == OutKind::pc2) pc2_ = std::make_unique<io::Pc2Writer>(file, p, timing.pc2_start, timing.pc2_rate);
    if (kind == OutKind::mdd) mdd_ = std::make_unique<io::MddWriter>(file, p, timing.mdd_times);
    if (part.surface) surface_ = *part.surface;
    normals_ = part.has_normals();
    if (kind == OutKind::gltf) {
      if (!part.surface) throw std::runtime_error("--out " + pattern + ": a glTF needs a surface mesh, not points");
      gltf_ = std::make_unique<io::GltfWriter>(file, surface_);
      gltf_times_ = timing.gltf_times;
    }
  }

  // the part's positions p x d (double), normals p x 3 or empty
  void write(int k, const Eigen::Ref<const Eigen::MatrixXd>& positions, const Eigen::Ref<const Eigen::MatrixXd>& normals) {
    full_.resize(positions.rows(), positions.cols() + extra_.cols());
    full_ << positions, extra_;
    if (kind_ == OutKind::pc2) return pc2_->append(full_);
    if (kind_ == OutKind::mdd) return mdd_->append(full_);
    if (kind_ == OutKind::gltf) {
      surface_.V = Eigen::MatrixXd::Zero(full_.rows(), 3);
      surface_.V.leftCols(full_.cols()) = full_;
      const double t = gltf_times_.at(static_cast<std::size_t>(k));
      return normals_ ? gltf_->append(t, surface_.V, normals) : gltf_->append(t, surface_.V);
    }
    const fs::path file = io::numbered_file(pattern_, k);
    const io::FileFormat* f = io::file_format(file);
    if (f->kind == io::FileKind::points) return io::write_points(file, full_);
    surface_.V = Eigen::MatrixXd::Zero(full_.rows(), 3);
    surface_.V.leftCols(full_.cols()) = full_;
    surface_.N = normals_ ? Eigen::MatrixXd(normals) : Eigen::MatrixXd();
    io::write_surface(file, surface_);
  }
  // the part's positions p x 3 floats, interleaved (the float kernel's output, a cache's layout)
  void write(const float* xyz) {
    if (pc2_) pc2_->append(xyz);
    else mdd_->append(xyz);
  }
  void finish() {
    if (pc2_) pc2_->finish();
    if (mdd_) mdd_->finish();
    if (gltf_) gltf_->finish();
  }

 private:
  OutKind kind_;
  std::string pattern_;
  Eigen::MatrixXd extra_;  // the part's columns beyond d
  bool normals_ = false;   // its file had normals: its frames get the deformed ones
  std::unique_ptr<io::Pc2Writer> pc2_;
  std::unique_ptr<io::MddWriter> mdd_;
  std::unique_ptr<io::GltfWriter> gltf_;
  std::vector<double> gltf_times_;
  io::SurfaceMesh surface_;
  Eigen::MatrixXd full_;
};

// Every --out, one a dense part, fed the rows of its part.
class FrameWriter {
 public:
  FrameWriter(const std::vector<Out>& outs, const io::OutputSet& outputs, const Model& m, const Timing& timing)
      : model_(m) {
    for (std::size_t k = 0; k < outs.size(); ++k) {
      const DensePart& part = m.dense.parts[k];
      const fs::path file = outs[k].kind == OutKind::numbered ? fs::path() : outputs.staging(outs[k].index);
      parts_.push_back(std::make_unique<PartWriter>(outs[k].kind, file, outs[k].name, part,
                                                    m.P_extra.middleRows(part.first, part.rows), timing));
    }
  }
  // positions p x d (double), normals p x 3 or empty
  void write(int k, const Eigen::MatrixXd& positions, const Eigen::MatrixXd& normals) {
    for (std::size_t i = 0; i < parts_.size(); ++i) {
      const DensePart& part = model_.dense.parts[i];
      const Eigen::MatrixXd none;
      parts_[i]->write(k, positions.middleRows(part.first, part.rows),
                       normals.size() > 0 ? normals.middleRows(part.first, part.rows) : none.middleRows(0, 0));
    }
  }
  // positions p x 3 floats, row-major
  void write(const interp::RowMatrixXf& xyz) {
    for (std::size_t i = 0; i < parts_.size(); ++i) parts_[i]->write(xyz.data() + 3 * model_.dense.parts[i].first);
  }
  void finish() {
    for (auto& p : parts_) p->finish();
  }

 private:
  const Model& model_;
  std::vector<std::unique_ptr<PartWriter>> parts_;
};

// Every output, numbered files expanded, checked together before any work: each follows the
// overwrite rule on its own, and no two (two series, a series and a cache, glTF or --stats)
// name one file.
void check_outputs(const SequenceArgs& a, const std::vector<Out>& outs, const std::vector<fs::path>& inputs, int frames) {
  std::error_code ec;
  std::map<fs::path, std::string> taken;  // canonical name -> the option and name that took it
  auto take = [&](const fs::path& f, const std::string& what) {
    const auto [it, fresh] = taken.emplace(fs::weakly_canonical(fs::absolute(f, ec), ec), what + " " + f.string());
    if (!fresh) throw std::runtime_error(what + " " + f.string() + ": is also another output of this command (" + it->second + ")");
  };
  for (const Out& o : outs)
    if (o.kind != OutKind::numbered) take(o.name, "--out");
  if (!a.stats.empty()) take(a.stats, "--stats");
  for (const Out& o : outs) {
    if (o.kind != OutKind::numbered) continue;
    for (int k = 0; k < frames; ++k) {
      const fs::path f = io::numbered_file(o.name, k);
      take(f, "--out " + o.name + ": frame " + std::to_string(k) + ":");
      io::OutputSet one(inputs, a.force);
      one.add(f, "--out");
    }
  }
}

class Progress {
 public:
  explicit Progress(int total) : total_(total), tty_(isatty(fileno(stderr)) != 0) {}
  void show(int done) {
    if (!tty_) return;
    const int w = 30, filled = total_ > 0 ? w * done / total_ : w;
    std::fprintf(stderr, "\r[%s%s] %3d%%  frame %d/%d  %.1f s", std::string(filled, '#').c_str(),
                 std::string(w - filled, ' ').c_str(), total_ > 0 ? 100 * done / total_ : 100, done, total_,
                 ms_since(t0_) / 1000);
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

// How the frames went.
struct Run {
  int done = 0, frames = 0, signal = 0;
  std::string failure;
  double embed_ms = 0, precompute_ms = 0, read_ms = 0, deform_ms = 0, write_ms = 0;
};

void run_frames(const SequenceArgs& a, io::Trajectory& traj, const Model& m, pipeline::Deformer& deformer,
                FrameWriter& out, bool use_float, const StopOnSignal& stop, const io::OutputSet& outputs, Run& run) {
  Progress progress(traj.frames());
  Eigen::MatrixXd positions(m.P.rows(), m.dim()), normals;
  if (deformer.has_rest_normals()) normals.resize(m.P.rows(), 3);
  interp::RowMatrixXf xyz(use_float ? m.P.rows() : 0, 3);
  for (int k = 0; k < traj.frames() && !(run.signal = stop.signal()); ++k) {
    try {
      if (k == 1) test_signal_at("frame");
      auto t0 = Clock::now();
      const Eigen::MatrixXd X = to_pose(traj.read(k), m, traj.where(k), a.control);
      run.read_ms += ms_since(t0);
      t0 = Clock::now();
      if (use_float) deformer.deform_float(X, xyz);
      else if (normals.size() > 0) deformer.deform(X, positions, normals);
      else deformer.deform(X, positions);
      run.deform_ms += ms_since(t0);
      t0 = Clock::now();
      if (use_float) out.write(xyz);
      else out.write(k, positions, normals);
      run.write_ms += ms_since(t0);
    } catch (const std::exception& e) {
      const std::string what = outputs.name_targets(e.what());
      run.failure = what.find("frame " + std::to_string(k)) == std::string::npos ? "frame " + std::to_string(k) + ": " + what : what;
      break;
    }
    run.done = k + 1;
    progress.show(run.done);
  }
  progress.end(run.done);
}

nlohmann::json stats_json(const SequenceArgs& a, const Model& m, const pipeline::Deformer& deformer, int frames,
                          const Run& run) {
  nlohmann::json j;
  j["method"] = pipeline::method_name(a.method);
  j["dim"] = m.dim();
  if (pipeline::needs_solve(a.method)) {
    j["alpha"] = deformer.solver().alpha();
    j["beta"] = deformer.solver().beta();
  }
  j["pin_boundary"] = a.pin_boundary;
  j["control_vertices"] = m.control.U.rows();
  j["elements"] = m.control.T.rows();
  j["points"] = m.P.rows();
  j["outside_points"] = deformer.embedding().outside.size();
  j["max_outside_distance"] = deformer.embedding().max_outside_distance;
  j["frames"] = run.done;
  j["frames_in_trajectory"] = frames;
  if (!run.failure.empty()) j["failure"] = run.failure;
  if (run.signal) j["interrupted_by_signal"] = run.signal;
  const double n = std::max(run.done, 1);
  j["timings_ms"] = {{"embed", run.embed_ms},         {"precompute", run.precompute_ms},
                     {"read", run.read_ms},           {"deform", run.deform_ms},
                     {"write", run.write_ms},         {"read_per_frame", run.read_ms / n},
                     {"deform_per_frame", run.deform_ms / n}, {"write_per_frame", run.write_ms / n}};
  return j;
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

void print_summary(const SequenceArgs& a, const Model& m, const pipeline::Deformer& deformer, int frames, const Run& run) {
  const int d = m.dim();
  std::printf("control: %s: %d vertices, %d %s (%dD)\n", a.control.c_str(), static_cast<int>(m.control.U.rows()),
              static_cast<int>(m.control.T.rows()), d == 3 ? "tetrahedra" : "triangles", d);
  std::printf("dense:   %s: %d points (%zu outside)\n", m.dense.names().c_str(), static_cast<int>(m.P.rows()),
              deformer.embedding().outside.size());
  std::printf("method:  %s", pipeline::method_name(a.method));
  if (pipeline::needs_solve(a.method))
    std::printf(", alpha %.4g, beta %.4g", deformer.solver().alpha(), deformer.solver().beta());
  std::printf("%s\nframes:  %d of %d from %s into %s\n", a.pin_boundary ? ", boundary pinned" : "", run.done, frames,
              a.deformed.c_str(), joined(a.outs).c_str());
  const double n = std::max(run.done, 1);
  std::printf("times (ms): embed %.2f  precompute %.2f  per frame: read %.3f  deform %.3f  write %.3f\n", run.embed_ms,
              run.precompute_ms, run.read_ms / n, run.deform_ms / n, run.write_ms / n);
}

// The embedding and the precompute, timed into `run`; with rest normals when `normals`.
pipeline::Deformer make_deformer(const SequenceArgs& a, const Model& m, bool normals, Run& run) {
  auto t0 = Clock::now();
  interp::Embedding emb;
  try {
    emb = interp::embed(m.control.U, m.control.T, m.P);
  } catch (const mbi::Error& e) {
    throw std::runtime_error(m.dense.names() + ": " + e.what());
  }
  run.embed_ms = ms_since(t0);
  if (!emb.outside.empty())
    std::fprintf(stderr, "mbi deform: warning: %zu of %d points lie outside the control mesh (farthest %.3g); they follow "
                 "the nearest element by extrapolation\n", emb.outside.size(), emb.size(), emb.max_outside_distance);
  if (a.max_outside) refuse_far_points(emb, m.control.U, m.control.T, m.P, *a.max_outside, m.dense.names(), a.control);
  test_signal_at("precompute");
  pipeline::DeformerOptions opt{.method = a.method, .interp = {}};
  opt.interp.alpha = a.alpha;
  opt.interp.pin_boundary = a.pin_boundary;
  t0 = Clock::now();
  try {
    pipeline::Deformer deformer(m.control.U, m.control.T, std::move(emb), opt,
                                normals ? m.dense.normals() : Eigen::MatrixXd());
    run.precompute_ms = ms_since(t0);
    return deformer;
  } catch (const mbi::Error& e) {
    throw std::runtime_error(a.control + ": " + e.what());
  }
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

// Everything from the models to the last frame; `outputs` holds the caches, glTF and --stats.
int run_sequence_frames(const SequenceArgs& a, const std::vector<Out>& outs, io::Trajectory& traj,
                        io::OutputSet& outputs, std::size_t i_stats) {
  test_signal_at("load");
  const Model m = load_model(a);
  const int d = m.dim();
  scenes::check_run_size(a.control, m.P.rows(), m.control.U.rows(), m.control.T.rows(), d);
  if (traj.frames() == 0) throw std::runtime_error(a.deformed + ": no frames");
  to_pose(traj.read(0), m, traj.where(0), a.control);  // a wrong node count fails before any work
  // numbered surfaces and glTF get deformed normals when their part has normals; caches hold
  // positions only, and take the float kernel (its output is their layout) for a 3D model
  bool normals = false, use_float = d == 3 && m.P_extra.cols() == 0, per_frame_times = false;
  std::string timed_out;
  for (const Out& o : outs) {
    if (o.kind == OutKind::mdd || o.kind == OutKind::gltf) per_frame_times = true, timed_out = o.name;
    normals |= (o.kind == OutKind::gltf || (o.kind == OutKind::numbered && io::is_surface_file(o.name)));
    use_float &= o.kind == OutKind::pc2 || o.kind == OutKind::mdd;
  }
  normals = normals && d == 3 && m.dense.normals().rows() > 0;
  Run run;
  run.frames = traj.frames();
  const Timing timing = output_timing(traj, a.fps, per_frame_times, timed_out);
  pipeline::Deformer deformer = make_deformer(a, m, normals, run);
  // From the first frame to the last rename a signal stops the frames, and what was done is
  // finished (signals.hpp); before, it ends the process at once with nothing written.
  const StopOnSignal stop;
  try {
    FrameWriter out(outs, outputs, m, timing);
    run_frames(a, traj, m, deformer, out, use_float, stop, outputs, run);
    if (run.done == 0 && run.signal) {
      std::fprintf(stderr, "mbi deform: interrupted by %s before the first frame: nothing written\n",
                   run.signal == SIGINT ? "SIGINT" : "SIGTERM");
      return 128 + run.signal;
    }
    if (run.done == 0) throw std::runtime_error(run.failure);
    test_signal_at("finish");
    out.finish();
  } catch (const std::exception& e) {
    throw std::runtime_error(outputs.name_targets(e.what()));
  }
  if (!a.stats.empty()) {
    if (!run.signal) run.signal = stop.signal();
    const nlohmann::json j = stats_json(a, m, deformer, traj.frames(), run);
    check_finite(j, a.stats);
    io::write_text_atomic(outputs.staging(i_stats), j.dump(2) + "\n");
  }
  outputs.commit();
  if (!run.signal) run.signal = stop.signal();
  print_summary(a, m, deformer, traj.frames(), run);
  return report_stop(run);
}

}  // namespace

bool is_sequence(const std::string& deformed, const std::vector<std::string>& outs) {
  if (io::Trajectory::names_trajectory(deformed)) return true;
  for (const std::string& out : outs) {
    const std::string ext = io::lower_extension(out);
    if (ext == ".pc2" || ext == ".mdd" || io::is_numbered_name(out)) return true;
  }
  return false;
}

double parse_fps(const std::string& text) {
  char* end = nullptr;
  const double fps = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(fps) || !(fps > 0))
    throw std::runtime_error("--fps " + text + ": give a number of frames per second > 0 (e.g. 24 or 29.97)");
  return fps;
}

int run_deform_sequence(const SequenceArgs& a) {
  for (const auto& [flag, v] : {std::pair{"--control", &a.control}, {"--deformed", &a.deformed}})
    if (v->empty()) throw std::runtime_error(std::string(flag) + " is required");
  if (a.meshes.empty() || a.outs.size() != a.meshes.size())
    throw std::runtime_error("give one --out for each --mesh (" + std::to_string(a.meshes.size()) + " --mesh, " +
                             std::to_string(a.outs.size()) + " --out)");
  if (a.alpha) check_option("--alpha", [&] { interp::check_alpha(*a.alpha); });
  if (!(a.fps > 0) || !std::isfinite(a.fps)) throw std::runtime_error("--fps " + short_number(a.fps) + ": must be > 0");
  std::vector<Out> outs;
  for (const std::string& o : a.outs) outs.push_back({.name = o, .kind = out_kind(o)});
  io::Trajectory traj(a.deformed);  // the list of frames; every file named exists
  check_fps(a.fps, traj.frames());
  // One overwrite rule (docs/cli.md): every output checked before any work, inputs never outputs.
  std::vector<fs::path> inputs = traj.files();
  inputs.insert(inputs.end(), a.meshes.begin(), a.meshes.end());
  for (const fs::path& p : io::control_mesh_files(a.control)) inputs.push_back(p);
  io::OutputSet outputs(inputs, a.force);
  for (Out& o : outs)
    if (o.kind != OutKind::numbered) o.index = outputs.add(o.name, "--out");
  const std::size_t i_stats = a.stats.empty() ? 0 : outputs.add(a.stats, "--stats");
  check_outputs(a, outs, inputs, traj.frames());
  return run_sequence_frames(a, outs, traj, outputs, i_stats);
}

}  // namespace mbi::cli
