#include "session_io.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

namespace mbi::viewer {
namespace {

nlohmann::json xyz(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

std::string format(const Event& e) {
  std::ostringstream o;
  o << e.frame << ' ';
  switch (e.kind) {
    case Event::Press: o << "press " << e.x << ' ' << e.y << ' ' << e.button; break;
    case Event::Move: o << "move " << e.x << ' ' << e.y; break;
    case Event::Release: o << "release " << e.x << ' ' << e.y << ' ' << e.button; break;
    case Event::Scroll: o << "scroll " << e.dy; break;
    case Event::Key: o << "key " << e.key; break;
  }
  return o.str();
}

std::deque<Event> read_script(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ViewerError(file.string() + ": cannot read the script");
  std::deque<Event> events;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    Event e;
    std::string kind;
    if (!(s >> e.frame >> kind) || e.frame < 0)
      throw ViewerError(file.string() + ":" + std::to_string(number) + ": expected FRAME EVENT ...");
    bool ok = true;
    if (kind == "press") e.kind = Event::Press, ok = bool(s >> e.x >> e.y >> e.button);
    else if (kind == "move") e.kind = Event::Move, ok = bool(s >> e.x >> e.y);
    else if (kind == "release") e.kind = Event::Release, ok = bool(s >> e.x >> e.y >> e.button);
    else if (kind == "scroll") e.kind = Event::Scroll, ok = bool(s >> e.dy);
    else if (kind == "key") e.kind = Event::Key, ok = bool(s >> e.key);
    else throw ViewerError(file.string() + ":" + std::to_string(number) + ": unknown event '" + kind + "'");
    if (!ok || !std::isfinite(e.x) || !std::isfinite(e.y) || !std::isfinite(e.dy))
      throw ViewerError(file.string() + ":" + std::to_string(number) + ": bad arguments for '" + kind + "'");
    events.push_back(e);
  }
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.frame < b.frame; });
  return events;
}

void Inputs::open(const std::filesystem::path& script, const std::filesystem::path& record) {
  if (!script.empty()) script_ = read_script(script);
  if (!record.empty()) {
    record_.open(record);
    if (!record_) throw ViewerError(record.string() + ": cannot write the recording");
    record_.precision(10);
  }
}

void Inputs::push(const Event& e) {
  queue_.push_back(e);
  if (record_.is_open()) record_ << format(e) << "\n";
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

nlohmann::json frame_report(const Stage& stage, const Interaction& in, const FrameTimes& times,
                            const Eigen::MatrixXd& X3, const Camera& camera, const WindowSize& window,
                            bool controls_on_screen) {
  const pipeline::FramePipeline& pipe = stage.pipe;
  const Eigen::MatrixXd& X = pipe.control_positions();
  nlohmann::json fr;
  fr["frame"] = pipe.frame();
  fr["direct"] = in.direct();
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
  if (controls_on_screen) {
    const int last = static_cast<int>(stage.views.size()) - 1;
    const double vw = stage.view_width(window);
    nlohmann::json cs = nlohmann::json::array();
    for (Eigen::Index i = 0; i < X3.rows(); ++i) {
      const Eigen::Vector2d q = camera.project(X3.row(i).transpose(), static_cast<int>(std::lround(vw)), window.height);
      cs.push_back({q.x() + last * vw, q.y()});
    }
    fr["control_window"] = cs;
  }
  return fr;
}
}  // namespace mbi::viewer
