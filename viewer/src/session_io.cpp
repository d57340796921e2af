#include "session_io.hpp"

#include "crease_layer.hpp"
#include "video.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <utility>

namespace mbi::viewer {
namespace {

namespace fs = std::filesystem;

nlohmann::json xyz(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

// The process's resident memory (VmRSS of /proc/self/status) in kB; -1 where there is none.
long long resident_kb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atoll(line.c_str() + 6);
  return -1;
}

// A writer's message about the reserved file, about the target instead (the user never named
// the reserved file).
std::string about(std::string what, const fs::path& staging, const std::string& target) {
  const std::string s = staging.string();
  for (std::size_t at = what.find(s); at != std::string::npos; at = what.find(s, at + target.size()))
    what.replace(at, s.size(), target);
  return what;
}

// The PNG at `staging`, errors naming `target`.
void write_png_for(const fs::path& staging, const io::Image& image, const std::string& target) {
  try {
    io::write_png(staging, image);
  } catch (const mbi::Error& e) {
    throw Error(about(e.what(), staging, target));
  }
}

}  // namespace

SessionFiles::SessionFiles(const ViewerOptions& o) : inputs_(o.inputs), force_(o.force) {
  if (!o.script.empty()) inputs_.push_back(o.script);
  outputs_ = std::make_unique<io::OutputSet>(inputs_, force_);
  std::optional<std::size_t> record, report;
  if (!o.record.empty()) record = outputs_->add(o.record, "--record");
  if (!o.screenshot.empty()) screenshot_ = outputs_->add(o.screenshot, "--screenshot");
  if (!o.report.empty()) report = outputs_->add(o.report, "--report");
  if (!o.video.empty()) {
    ffmpeg_ = find_ffmpeg(o.video, "--video");  // before the window opens
    video_ = outputs_->add(o.video, "--video");
  }
  for (const fs::path& p : {o.record, o.screenshot, o.report, o.video})
    if (!p.empty()) targets_.push_back(p);
  if (!o.script.empty()) {
    try {
      script_ = read_script(o.script);
    } catch (const mbi::Error& e) {
      throw Error(std::string("--script ") + e.what());
    }
  }
  // a header line: a recording of no event is still written (and replays as nothing)
  if (record) open(record_, "--record", *record, "# mbi view recording: FRAME EVENT ARGS\n");
  if (report) open(report_, "--report", *report, "[");
}

SessionFiles::~SessionFiles() {
  for (Stream* s : {&record_, &report_})
    if (s->file) std::fclose(s->file);
  // outputs_ then removes every reserved file: no output created or replaced
}

void SessionFiles::open(Stream& s, const std::string& option, std::size_t output, const char* first) {
  s.option = option;
  s.target = outputs_->target(output);
  s.file = std::fopen(outputs_->staging(output).c_str(), "wb");
  if (!s.file)
    throw Error(option + " " + s.target.string() + ": cannot open for writing (" + std::strerror(errno) + ")");
  write(s, first);
}

void SessionFiles::write(Stream& s, const std::string& text) {
  if (!s.file || s.error) return;
  if (std::fwrite(text.data(), 1, text.size(), s.file) != text.size()) s.error = errno ? errno : EIO;
}

void SessionFiles::fail(const Stream& s) const {
  throw Error(s.option + " " + s.target.string() + ": write error (" + std::strerror(s.error) + ")");
}

void SessionFiles::close(Stream& s) {
  if (!s.file) return;
  if ((std::fflush(s.file) != 0 || std::ferror(s.file)) && !s.error) s.error = errno ? errno : EIO;
  if (std::fclose(s.file) != 0 && !s.error) s.error = errno ? errno : EIO;
  s.file = nullptr;
  if (s.error) fail(s);
}

void SessionFiles::record(const Event& e) { write(record_, format(e) + "\n"); }

void SessionFiles::report(const nlohmann::json& frame) {
  write(report_, (report_empty_ ? "\n" : ",\n") + frame.dump());
  report_empty_ = false;
}

void SessionFiles::check() {
  // the recording reaches the disk each frame (a full disk shows at once); the report when
  // its buffer fills
  if (record_.file && !record_.error && std::fflush(record_.file) != 0) record_.error = errno ? errno : EIO;
  for (const Stream* s : {&record_, &report_})
    if (s->error) fail(*s);
}

std::unique_ptr<io::OutputSet> SessionFiles::reserve(const fs::path& name) const {
  const fs::path here = fs::absolute(name).lexically_normal();
  for (const fs::path& t : targets_)
    if (fs::absolute(t).lexically_normal() == here)
      throw Error(name.string() + ": is also an output of this session (" + t.string() + ")");
  auto one = std::make_unique<io::OutputSet>(inputs_, force_);
  one->add(name, "");
  return one;
}

void SessionFiles::snapshot(const fs::path& name, const io::Image& image) const {
  const std::unique_ptr<io::OutputSet> one = reserve(name);
  write_png_for(one->staging(0), image, name.string());
  one->commit();
}

fs::path SessionFiles::video_staging() const { return video_ ? outputs_->staging(*video_) : fs::path(); }

void SessionFiles::finish(const io::Image& last_shot) {
  if (finished_) return;
  write(report_, "\n]\n");
  close(record_);
  close(report_);
  if (screenshot_) write_png_for(outputs_->staging(*screenshot_), last_shot, "--screenshot " + outputs_->target(*screenshot_).string());
  outputs_->commit();
  finished_ = true;
}

void Inputs::open(SessionFiles& files) {
  files_ = &files;
  script_ = files.take_script();
}

void Inputs::push(const Event& e) {
  queue_.push_back(e);
  if (files_) files_->record(e);
}

std::deque<Event> Inputs::take(int frame) {
  while (!script_.empty() && script_.front().frame <= frame) {
    Event e = script_.front();
    e.frame = frame;
    push(e);
    script_.pop_front();
  }
  return std::exchange(queue_, {});
}

namespace {

// The crease colours of this frame: the scale, the legend's bar, per view its mean face jump and
// the mean scale position (0 cold .. 1 hot) of its dense points near interior faces.
nlohmann::json creases_report(const CreaseLayer& creases, const Stage& stage) {
  nlohmann::json views = nlohmann::json::array();
  for (size_t k = 0; k < creases.views().size() && k < stage.views.size(); ++k)
    views.push_back({{"label", pipeline::method_name(stage.views[k])},
                     {"mean_jump", creases.views()[k].mean_jump},
                     {"mean_near", creases.views()[k].mean_near}});
  const Rect& l = creases.legend;
  return {{"top", creases.top()}, {"legend", {l.x, l.y, l.w, l.h}}, {"views", views}};
}

// Surface contact now: on or off, the points touching (the driver's count), the contact
// points' mean position and each collider's pose, its window position in the last view and
// its gap (the least signed distance of a contact point to it, m: negative is a penetration).
nlohmann::json contact_report(const Stage& stage, const Interaction& in, const pipeline::SurfaceContact& contact,
                              const Camera& camera, const WindowSize& window) {
  const Eigen::MatrixXd X = stage.pipe.control_positions().transpose();  // 3 x n: x y z of each node
  const Eigen::MatrixXd P = contact.points(Eigen::Map<const Eigen::VectorXd>(X.data(), X.size()));
  const Rect& r = stage.layout.views.back();
  nlohmann::json cs = nlohmann::json::array();
  double deepest = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < contact.colliders().size(); ++i) {
    const pipeline::Collider c = pipeline::posed(contact.colliders()[i], stage.time());
    double gap = std::numeric_limits<double>::infinity();
    for (Eigen::Index p = 0; p < P.rows(); ++p) gap = std::min(gap, pipeline::signed_distance(c, P.row(p).transpose(), 0).value);
    deepest = std::min(deepest, gap);
    const Eigen::Vector2d q = camera.project(c.point, static_cast<int>(std::lround(r.w)), window.height);
    cs.push_back({{"shape", scenes::kColliderShapeNames.name(c.shape)},
                  {"point", xyz(c.point)},
                  {"window", {q.x() + r.x, q.y()}},
                  {"gap", gap},
                  {"grabbed", in.grabbed_collider() == static_cast<int>(i)}});
  }
  const pipeline::SimulatorDriver* sd = stage.simulation();
  nlohmann::json j = {{"on", stage.contact_on()},
                      {"touching", sd ? sd->touching_points() : 0},
                      {"points", contact.contact_points()},
                      {"points_mean", xyz(P.colwise().mean().transpose())},
                      {"max_depth", contact.max_depth()},
                      {"deepest", deepest},
                      {"colliders", cs}};
  if (in.grabbed_collider() >= 0)
    j["drag"] = {{"collider", in.grabbed_collider()}, {"grab", xyz(in.collider_grab())}, {"target", xyz(in.collider_target())}};
  return j;
}

}  // namespace

nlohmann::json frame_report(const Stage& stage, const Interaction& in, const FrameTimes& times,
                            const Eigen::MatrixXd& X3, const Camera& camera, const WindowSize& window,
                            bool controls_on_screen) {
  const pipeline::FramePipeline& pipe = stage.pipe;
  const Eigen::MatrixXd& X = pipe.control_positions();
  nlohmann::json fr;
  fr["frame"] = pipe.frame();
  fr["direct"] = in.direct();
  fr["method"] = pipeline::method_name(pipe.method());
  fr["alpha"] = stage.alpha;
  auto rect = [](const Rect& r) { return nlohmann::json{r.x, r.y, r.w, r.h}; };
  nlohmann::json views = nlohmann::json::array();
  for (size_t k = 0; k < stage.layout.views.size(); ++k)
    views.push_back({{"rect", rect(stage.layout.views[k])}, {"viewport", rect(stage.layout.view_viewports[k])},
                     {"label", pipeline::method_name(stage.views[k])}});
  fr["layout"] = {{"window", {window.width, window.height}}, {"panel", rect(stage.layout.panel)}, {"views", views}};
  fr["evaluator"] = {{"name", stage.evaluator.name()}, {"why", stage.evaluator_why}};
  fr["looks"] = stage.looks;
  fr["dense_points"] = stage.rest_dense.rows();
  fr["finite"] = X.allFinite();
  fr["timings_ms"] = {{"simulation", pipe.timings().drive_ms}, {"solve", pipe.timings().solve_ms},
                      {"interpolation", times.interpolation_ms}, {"drawing", times.drawing_ms}};
  fr["max_displacement"] = (X - stage.U).rowwise().norm().maxCoeff();
  if (const pipeline::SimulatorDriver* sd = stage.simulation()) {
    fr["kinetic_energy"] = sd->simulator().kinetic_energy();
    fr["elastic_energy"] = sd->simulator().elastic_energy();
  }
  if (const Poke& poke = in.poke(); poke.handle >= 0) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) p += poke.bary(k) * pad3(X.row(stage.T(poke.element, k)));
    fr["poke"] = {{"point", xyz(p)}, {"target", xyz(poke.target)}, {"stiffness", poke.stiffness}};
  }
  nlohmann::json hs = nlohmann::json::array();
  for (size_t h = 0; h < in.handles().size(); ++h) {
    const int v = in.handles()[h];
    hs.push_back({{"vertex", v},
                  {"position", xyz(pad3(X.row(v)))},
                  {"target", xyz(pad3(in.handle_targets().row(static_cast<Eigen::Index>(h))))}});
  }
  fr["handles"] = hs;
  fr["camera"] = {{"target", xyz(camera.target)}, {"radius", camera.radius}, {"yaw", camera.yaw}, {"pitch", camera.pitch}};
  if (const long long kb = resident_kb(); kb >= 0) fr["resident_kb"] = kb;
  if (controls_on_screen) {
    const Rect& r = stage.layout.views.back();
    nlohmann::json cs = nlohmann::json::array();
    for (Eigen::Index i = 0; i < X3.rows(); ++i) {
      const Eigen::Vector2d q = camera.project(X3.row(i).transpose(), static_cast<int>(std::lround(r.w)), window.height);
      cs.push_back({q.x() + r.x, q.y()});
    }
    fr["control_window"] = cs;
  }
  if (stage.creases && stage.creases->shown) fr["creases"] = creases_report(*stage.creases, stage);
  if (const pipeline::SurfaceContact* c = stage.contact(); c && stage.d == 3)
    fr["contact"] = contact_report(stage, in, *c, camera, window);
  return fr;
}
}  // namespace mbi::viewer
