// mbi deform's outputs (deform_outputs.hpp).
#include "deform_outputs.hpp"

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <stdexcept>

namespace fs = std::filesystem;

namespace mbi::cli {
namespace {

bool is_point_list(const fs::path& p) {
  const io::FileFormat* f = io::file_format(p);
  return f && f->kind == io::FileKind::points;
}

OutKind sequence_kind(const std::string& out) {
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

bool is_gltf(const fs::path& p) {
  const std::string ext = io::lower_extension(p);
  return ext == ".glb" || ext == ".gltf";
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

}  // namespace

std::vector<Out> output_kinds(const std::vector<std::string>& outs, bool trajectory) {
  std::vector<Out> o;
  for (const std::string& name : outs) o.push_back({.name = name, .kind = trajectory ? sequence_kind(name) : OutKind::file});
  return o;
}

void reserve_outputs(std::vector<Out>& outs, io::OutputSet& outputs) {
  for (Out& o : outs) {
    if (o.kind == OutKind::numbered) continue;
    o.index = outputs.add(o.name, "--out");
    if (o.kind == OutKind::file && !is_point_list(o.name) && !io::is_surface_file(o.name))
      throw std::runtime_error("--out " + o.name + ": unknown output format '" + io::lower_extension(o.name) +
                               "' (expected " + io::extensions_of(io::FileKind::surface) + ", .txt or .xyz)");
  }
}

void check_outputs(const std::vector<Out>& outs, const std::string& stats, const std::vector<fs::path>& inputs,
                   bool force, int frames) {
  std::error_code ec;
  std::map<fs::path, std::string> taken;  // canonical name -> the option and name that took it
  auto take = [&](const fs::path& f, const std::string& what) {
    const auto [it, fresh] = taken.emplace(fs::weakly_canonical(fs::absolute(f, ec), ec), what + " " + f.string());
    if (!fresh) throw std::runtime_error(what + " " + f.string() + ": is also another output of this command (" + it->second + ")");
  };
  for (const Out& o : outs)
    if (o.kind != OutKind::numbered) take(o.name, "--out");
  if (!stats.empty()) take(stats, "--stats");
  for (const Out& o : outs) {
    if (o.kind != OutKind::numbered) continue;
    for (int k = 0; k < frames; ++k) {
      const fs::path f = io::numbered_file(o.name, k);
      take(f, "--out " + o.name + ": frame " + std::to_string(k) + ":");
      io::OutputSet one(inputs, force);
      one.add(f, "--out");
    }
  }
}

Timing output_timing(Frames& frames, std::optional<double> resampled, const std::vector<Out>& outs) {
  const io::Trajectory* t = frames.trajectory_file();
  if (!t) return {};
  if (resampled) {
    Timing o;
    o.pc2_start = static_cast<float>(frames.times().front() * *resampled);
    o.gltf_times = frames.times();
    for (double x : o.gltf_times) o.mdd_times.push_back(static_cast<float>(x));
    return o;
  }
  const double fps = kDefaultFps;
  std::string timed;  // an output that needs every frame's time
  for (const Out& o : outs)
    if (o.kind == OutKind::mdd || o.kind == OutKind::gltf) timed = o.name;
  if (timed.empty() && !t->has_times()) {
    Timing o;
    if (const auto pc2 = t->pc2_timing()) o.pc2_start = pc2->first, o.pc2_rate = pc2->second;
    return o;
  }
  if (t->frames() > kMaxTimedFrames)
    throw std::runtime_error("--out " + timed + ": " + std::to_string(t->frames()) + " frames of " + t->spec() +
                             " are more than the " + std::to_string(kMaxTimedFrames) +
                             " frames whose times a sequence holds (write a PC2 from a PC2, or fewer frames)");
  Timing o = cache_timing(*t, fps);
  o.gltf_times = increasing_times(o.mdd_times, fps);
  return o;
}

double parse_fps(const std::string& text) {
  char* end = nullptr;
  const double fps = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(fps) || !(fps > 0))
    throw std::runtime_error("--fps " + text + ": give a number of frames per second > 0 (e.g. 24 or 29.97)");
  return fps;
}

void check_fps(double fps, int frames) {
  if (!(fps > 0) || !std::isfinite(fps)) throw std::runtime_error("--fps " + short_number(fps) + ": must be > 0");
  const double last = std::max(frames - 1, 1);
  const float dt = static_cast<float>(1.0 / fps), end = static_cast<float>(last / fps);
  if (std::isnormal(dt) && std::isfinite(end)) return;
  char range[96];
  std::snprintf(range, sizeof range, "from %.3g to %.3g", last / static_cast<double>(FLT_MAX), 1.0 / FLT_MIN);
  throw std::runtime_error("--fps " + short_number(fps) + ": the times of " + std::to_string(frames) +
                           " frames at this rate are not finite and increasing as float32; give a rate " + range);
}

// Writes one dense part's frames as they come: into a point cache or an animated glTF (finished
// at the end, or at the last good frame), one numbered file a frame, or the one pose's file
// (kept until finish()).
class PartWriter {
 public:
  PartWriter(const Out& out, const io::OutputSet& outputs, const DensePart& part, const Eigen::MatrixXd& extra,
             const Timing& timing)
      : out_(out), outputs_(outputs), extra_(extra), normals_(part.has_normals()) {
    if (part.surface) surface_ = *part.surface;
    const fs::path file = out.kind == OutKind::numbered ? fs::path() : outputs.staging(out.index);
    const int p = static_cast<int>(part.rows);
    if (out.kind == OutKind::pc2) pc2_ = std::make_unique<io::Pc2Writer>(file, p, timing.pc2_start, timing.pc2_rate);
    if (out.kind == OutKind::mdd) mdd_ = std::make_unique<io::MddWriter>(file, p, timing.mdd_times);
    if (out.kind == OutKind::gltf) {
      if (!part.surface) throw std::runtime_error("--out " + out.name + ": a glTF needs a surface mesh, not points");
      gltf_ = std::make_unique<io::GltfWriter>(file, *part.surface);
      gltf_times_ = timing.gltf_times;
      warn(*gltf_);
    } else if (out.kind == OutKind::file && part.surface && is_gltf(out.name)) {
      warn(io::GltfWriter(file, *part.surface));  // what of the input does not map, before any work
    }
  }

  // the part's positions p x d (double), normals p x 3 or empty
  void write(int k, const Eigen::Ref<const Eigen::MatrixXd>& positions, const Eigen::Ref<const Eigen::MatrixXd>& normals) {
    full_.resize(positions.rows(), positions.cols() + extra_.cols());
    full_ << positions, extra_;
    if (out_.kind == OutKind::pc2) return pc2_->append(full_);
    if (out_.kind == OutKind::mdd) return mdd_->append(full_);
    normals_out_ = normals_ ? Eigen::MatrixXd(normals) : Eigen::MatrixXd();
    if (out_.kind == OutKind::file) return;  // written by finish()
    if (out_.kind == OutKind::gltf) {
      set_positions();
      const double t = gltf_times_.at(static_cast<std::size_t>(k));
      return normals_ ? gltf_->append(t, surface_.V, normals) : gltf_->append(t, surface_.V);
    }
    write_file(io::numbered_file(out_.name, k));
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
    if (out_.kind == OutKind::file) outputs_.write(out_.index, [&](const fs::path& p) { write_file(p, out_.name); });
  }

 private:
  void warn(const io::GltfWriter& w) const {
    for (const std::string& note : w.notes())
      std::fprintf(stderr, "mbi deform: warning: --out %s: %s\n", out_.name.c_str(), note.c_str());
  }
  // The last frame as one file (format by the extension of `name`): a surface keeps what its file
  // held besides positions; points alone make a vertices-only surface.
  void write_file(const fs::path& file, const fs::path& name = {}) {
    if (is_point_list(name.empty() ? file : name)) return io::write_points(file, full_);
    if (full_.cols() > 3)
      throw std::runtime_error(out_.name + ": points with " + std::to_string(full_.cols()) +
                               " coordinates cannot be written as a surface (use .txt/.xyz)");
    set_positions();
    surface_.N = normals_out_;
    io::write_surface(file, surface_);
  }
  // the part's surface (or a vertices-only one) at the current positions, z = 0 in 2D
  void set_positions() {
    surface_.V = Eigen::MatrixXd::Zero(full_.rows(), 3);
    surface_.V.leftCols(full_.cols()) = full_;
  }

  Out out_;
  const io::OutputSet& outputs_;
  Eigen::MatrixXd extra_;  // the part's columns beyond d
  bool normals_ = false;   // its file had normals: its frames get the deformed ones
  std::unique_ptr<io::Pc2Writer> pc2_;
  std::unique_ptr<io::MddWriter> mdd_;
  std::unique_ptr<io::GltfWriter> gltf_;
  std::vector<double> gltf_times_;
  io::SurfaceMesh surface_;
  Eigen::MatrixXd full_, normals_out_;
};

FrameWriter::FrameWriter(const std::vector<Out>& outs, const io::OutputSet& outputs, const Model& m,
                         const Timing& timing)
    : model_(m) {
  for (std::size_t k = 0; k < outs.size(); ++k) {
    const DensePart& part = m.dense.parts[k];
    parts_.push_back(
        std::make_unique<PartWriter>(outs[k], outputs, part, m.P_extra.middleRows(part.first, part.rows), timing));
  }
}

FrameWriter::~FrameWriter() = default;

void FrameWriter::write(int k, const Eigen::MatrixXd& positions, const Eigen::MatrixXd& normals) {
  const Eigen::MatrixXd none;
  for (std::size_t i = 0; i < parts_.size(); ++i) {
    const DensePart& part = model_.dense.parts[i];
    parts_[i]->write(k, positions.middleRows(part.first, part.rows),
                     normals.size() > 0 ? normals.middleRows(part.first, part.rows) : none.middleRows(0, 0));
  }
}

void FrameWriter::write(const interp::RowMatrixXf& xyz) {
  for (std::size_t i = 0; i < parts_.size(); ++i) parts_[i]->write(xyz.data() + 3 * model_.dense.parts[i].first);
}

void FrameWriter::finish() {
  for (auto& p : parts_) p->finish();
}

}  // namespace mbi::cli
