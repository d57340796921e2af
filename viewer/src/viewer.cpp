#include <mbi/gpu/renderer.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/io/atomic_file.hpp>
#include <mbi/viewer/camera.hpp>
#include <mbi/viewer/viewer.hpp>

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <sstream>

namespace mbi::viewer {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Event {
  int frame = 0;
  enum Kind { Press, Move, Release, Scroll, Key } kind = Move;
  double x = 0, y = 0, dy = 0;
  int button = 0;
  std::string key;
};

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

const char* key_name(int key) {
  switch (key) {
    case GLFW_KEY_SPACE: return "space";
    case GLFW_KEY_ESCAPE: return "escape";
    case GLFW_KEY_SLASH: return "?";
    default: break;
  }
  static char buf[2] = {0, 0};
  if (key >= GLFW_KEY_A && key <= GLFW_KEY_Z) {
    buf[0] = static_cast<char>('a' + (key - GLFW_KEY_A));
    return buf;
  }
  if (key >= GLFW_KEY_0 && key <= GLFW_KEY_9) {
    buf[0] = static_cast<char>('0' + (key - GLFW_KEY_0));
    return buf;
  }
  return nullptr;
}

const char* kHelp =
    "Mouse (left button):\n"
    "  on the model      poke: grab the surface, a spring pulls it to the cursor\n"
    "  direct mode       click a control vertex: it becomes a handle; drag it\n"
    "  on the background orbit (2D: pan)\n"
    "  right drag        pan; right click on a handle removes it\n"
    "  wheel / pinch     zoom\n"
    "Keys:\n"
    "  space  play / pause      n  one step        r  reset\n"
    "  d      direct mode on/off (drag handles, no physics)\n"
    "  m      next method       s  split view (BI | method)\n"
    "  w      control wireframe h  handle markers\n"
    "  f      frame the model   p  screenshot (mbi-screenshot-NNNN.png)\n"
    "  ?      this help         q / escape  quit";

}  // namespace

struct Viewer::Impl {
  ViewerOptions opt;
  GLFWwindow* window = nullptr;
  std::unique_ptr<gpu::Context> context;
  std::unique_ptr<gpu::Renderer> renderer;
  Camera camera;
  int frame = 0;
  std::deque<Event> script, queue;
  std::ofstream record;
  nlohmann::json report = nlohmann::json::array();
  bool help = false, step_once = false, close = false, direct = false;
  // interaction state
  enum class Drag { None, Orbit, Pan, Poke, Handle } drag = Drag::None;
  double last_x = 0, last_y = 0, mouse_x = 0, mouse_y = 0;
  int panel_of_drag = 0;
  Eigen::Vector2d panel_min = Eigen::Vector2d::Zero(), panel_max = Eigen::Vector2d::Zero();
  // poke
  int poke_handle = -1, poke_element = -1;
  Eigen::Vector4d poke_bary = Eigen::Vector4d::Zero();
  Eigen::Vector3d poke_plane = Eigen::Vector3d::Zero(), poke_target = Eigen::Vector3d::Zero();
  double poke_k = 0;
  // direct mode
  std::vector<int> handles;
  Eigen::MatrixXd handle_targets;
  int dragged_handle = -1;
  std::unique_ptr<pipeline::Driver> saved_driver;  // the simulation while in direct mode
  std::string message;
  double draw_ms = 0, fps = 0;
  Clock::time_point last_frame_time = Clock::now();
  io::Image last_shot;

  static void on_mouse_button(GLFWwindow* w, int button, int action, int) {
    auto* s = static_cast<Impl*>(glfwGetWindowUserPointer(w));
    if (ImGui::GetIO().WantCaptureMouse && action == GLFW_PRESS) return;
    double x, y;
    glfwGetCursorPos(w, &x, &y);
    Event e;
    e.frame = s->frame;
    e.kind = action == GLFW_PRESS ? Event::Press : Event::Release;
    e.x = x, e.y = y, e.button = button;
    s->push(e);
  }
  static void on_cursor(GLFWwindow* w, double x, double y) {
    auto* s = static_cast<Impl*>(glfwGetWindowUserPointer(w));
    if (s->drag == Drag::None) return;  // only drags matter (and keep recordings short)
    Event e;
    e.frame = s->frame;
    e.kind = Event::Move;
    e.x = x, e.y = y;
    s->push(e);
  }
  static void on_scroll(GLFWwindow* w, double, double dy) {
    auto* s = static_cast<Impl*>(glfwGetWindowUserPointer(w));
    if (ImGui::GetIO().WantCaptureMouse) return;
    Event e;
    e.frame = s->frame;
    e.kind = Event::Scroll;
    e.dy = dy;
    s->push(e);
  }
  static void on_key(GLFWwindow* w, int key, int, int action, int mods) {
    auto* s = static_cast<Impl*>(glfwGetWindowUserPointer(w));
    if (action != GLFW_PRESS || ImGui::GetIO().WantCaptureKeyboard) return;
    const char* name = key == GLFW_KEY_SLASH && (mods & GLFW_MOD_SHIFT) ? "?" : key_name(key);
    if (!name) return;
    Event e;
    e.frame = s->frame;
    e.kind = Event::Key;
    e.key = name;
    s->push(e);
  }
  void push(const Event& e) {
    queue.push_back(e);
    if (record.is_open()) record << format(e) << "\n";
  }

  int window_w() const {
    int w, h;
    glfwGetWindowSize(window, &w, &h);
    return std::max(w, 1);
  }
  int window_h() const {
    int w, h;
    glfwGetWindowSize(window, &w, &h);
    return std::max(h, 1);
  }
};

Viewer::Viewer(const ViewerOptions& options) : impl_(std::make_unique<Impl>()) {
  impl_->opt = options;
  if (!glfwInit()) {
    const char* why = nullptr;
    glfwGetError(&why);
    throw ViewerError(std::string("no display: cannot open a window (") + (why ? why : "GLFW failed") + ")");
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_TRUE);
  impl_->window = glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
  if (!impl_->window) {
    const char* why = nullptr;
    glfwGetError(&why);
    glfwTerminate();
    throw ViewerError(std::string("no OpenGL 3.3 window: ") + (why ? why : "GLFW failed"));
  }
  glfwMakeContextCurrent(impl_->window);
  glfwSwapInterval(options.frames > 0 ? 0 : 1);
  impl_->context = gpu::Context::adopt_current();
  impl_->renderer = std::make_unique<gpu::Renderer>(*impl_->context);
  glfwSetWindowUserPointer(impl_->window, impl_.get());
  glfwSetMouseButtonCallback(impl_->window, &Impl::on_mouse_button);
  glfwSetCursorPosCallback(impl_->window, &Impl::on_cursor);
  glfwSetScrollCallback(impl_->window, &Impl::on_scroll);
  glfwSetKeyCallback(impl_->window, &Impl::on_key);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui_ImplGlfw_InitForOpenGL(impl_->window, true);  // chains to the callbacks above
  ImGui_ImplOpenGL3_Init("#version 330 core");
  if (!options.script.empty()) impl_->script = read_script(options.script);
  if (!options.record.empty()) {
    impl_->record.open(options.record);
    if (!impl_->record) throw ViewerError(options.record.string() + ": cannot write the recording");
    impl_->record.precision(10);
  }
}

Viewer::~Viewer() {
  if (!impl_ || !impl_->window) return;
  impl_->renderer.reset();
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(impl_->window);
  glfwTerminate();
}

std::unique_ptr<gpu::GpuEvaluator> Viewer::evaluator() {
  gpu::GpuOptions o;
  o.measure = true;
  return std::make_unique<gpu::GpuEvaluator>(*impl_->context, o);
}

int Viewer::frame() const { return impl_->frame; }
ViewerOptions& Viewer::options() { return impl_->opt; }

io::Image Viewer::screenshot() { return impl_->last_shot; }

namespace {

io::Image read_framebuffer(int w, int h) {
  std::vector<std::uint8_t> rgba(static_cast<size_t>(w) * h * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  io::Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::uint8_t* s = rgba.data() + (static_cast<size_t>(h - 1 - y) * w + x) * 4;
      std::uint8_t* d = img.at(x, y);
      d[0] = s[0], d[1] = s[1], d[2] = s[2];
    }
  return img;
}

Eigen::Vector3d pad3(const Eigen::RowVectorXd& r) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  p.head(r.size()) = r.transpose();
  return p;
}

}  // namespace

int Viewer::show(pipeline::FramePipeline& pipe, const Eigen::MatrixXi& F, Callback per_frame,
                 const io::Image* image, Rebuild rebuild, double young, double poisson) {
  Impl& s = *impl_;
  auto* gpu_ev = dynamic_cast<gpu::GpuEvaluator*>(&pipe.evaluator());
  if (!gpu_ev) throw ViewerError("the viewer shows pipelines built with Viewer::evaluator()");
  const int d = pipe.dim();
  if (d == 2 && !image) throw ViewerError("a 2D pipeline needs an image to draw");
  s.renderer->set_faces(F);
  const Eigen::MatrixXd& U = pipe.rest_positions();
  const Eigen::MatrixXi& T = pipe.elements();
  const Eigen::MatrixXd rest_dense = interp::embedded_positions(U, T, pipe.embedding());
  // camera: frame the control mesh; 2D looks at the picture from the front (y down)
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
  lo.head(d) = U.colwise().minCoeff().transpose();
  hi.head(d) = U.colwise().maxCoeff().transpose();
  const double size = (hi - lo).norm();
  auto reset_view = [&] {
    if (d == 2) {
      s.camera.frame(lo, hi, Eigen::Vector3d(0, -1, 0));
      s.camera.yaw = std::acos(-1.0);
      s.camera.pitch = 0;
    } else {
      s.camera.frame(lo, hi, s.opt.up);
      s.camera.yaw = 0.6;
      s.camera.pitch = 0.35;
    }
  };
  reset_view();
  std::vector<pipeline::Method> panels;
  auto set_panels = [&] {
    panels.clear();
    if (s.opt.split && pipe.method() != pipeline::Method::BI) panels.push_back(pipeline::Method::BI);
    panels.push_back(pipe.method());
  };
  set_panels();
  auto sim_driver = [&]() -> pipeline::SimulatorDriver* {
    return dynamic_cast<pipeline::SimulatorDriver*>(&pipe.driver());
  };
  double alpha = pipe.options().interp.alpha > 0 ? pipe.options().interp.alpha : (d == 3 ? 0.1 : 0.2);
  pipe.step(false);  // frame 0

  // ------------------------------------------------------------------ interaction helpers
  auto panel_at = [&](double x) {
    const int n = static_cast<int>(panels.size());
    return std::clamp(static_cast<int>(x / (static_cast<double>(s.window_w()) / n)), 0, n - 1);
  };
  auto ray_at = [&](double x, double y, int panel) {
    const int n = static_cast<int>(panels.size());
    const double pw = static_cast<double>(s.window_w()) / n;
    return s.camera.ray(x - panel * pw, y, static_cast<int>(std::lround(pw)), s.window_h());
  };
  auto release_poke = [&] {
    if (s.poke_handle >= 0 && sim_driver() && sim_driver()->simulator().has_handle(s.poke_handle))
      sim_driver()->simulator().remove(s.poke_handle);
    s.poke_handle = -1;
  };
  auto current_X3 = [&] {
    Eigen::MatrixXd X3 = Eigen::MatrixXd::Zero(U.rows(), 3);
    X3.leftCols(d) = pipe.control_positions();
    return X3;
  };
  auto make_handle_driver = [&] {
    if (s.handles.empty()) {
      auto given = std::make_unique<pipeline::GivenDriver>(U);
      given->set(pipe.control_positions());
      pipe.set_driver(std::move(given));
      return;
    }
    interp::ControlOptions co;
    co.interp.alpha = alpha;
    auto driver = std::make_unique<pipeline::HandleDriver>(U, T, s.handles, co);
    driver->set_targets(s.handle_targets);
    pipe.set_driver(std::move(driver));
  };
  auto set_direct = [&](bool on) {
    if (on == s.direct) return;
    release_poke();
    s.direct = on;
    if (on) {
      s.handles.clear();
      s.handle_targets.resize(0, d);
      auto given = std::make_unique<pipeline::GivenDriver>(U);
      given->set(pipe.control_positions());
      s.saved_driver = pipe.set_driver(std::move(given));
    } else if (s.saved_driver) {
      pipe.set_driver(std::move(s.saved_driver));
    }
  };
  auto nearest_control_vertex = [&](double x, double y, int panel) {
    const Eigen::MatrixXd X3 = current_X3();
    const int n = static_cast<int>(panels.size());
    const double pw = static_cast<double>(s.window_w()) / n;
    int best = -1;
    double best_d = 12.0;  // pixels
    for (Eigen::Index i = 0; i < X3.rows(); ++i) {
      const Eigen::Vector2d q = s.camera.project(X3.row(i).transpose(), static_cast<int>(std::lround(pw)), s.window_h());
      const double dist = (q - Eigen::Vector2d(x - panel * pw, y)).norm();
      if (dist < best_d) best_d = dist, best = static_cast<int>(i);
    }
    return best;
  };
  auto handle_event = [&](const Event& e) {
    switch (e.kind) {
      case Event::Press: {
        s.last_x = e.x, s.last_y = e.y;
        if (e.x >= s.panel_min.x() && e.x <= s.panel_max.x() && e.y >= s.panel_min.y() && e.y <= s.panel_max.y())
          return;  // on the panel: not a poke
        const int panel = panel_at(e.x);
        s.panel_of_drag = panel;
        if (e.button == 1) {  // right: remove a handle, else pan
          if (s.direct) {
            const int v = nearest_control_vertex(e.x, e.y, panel);
            auto it = std::find(s.handles.begin(), s.handles.end(), v);
            if (v >= 0 && it != s.handles.end()) {
              const auto k = it - s.handles.begin();
              s.handles.erase(it);
              Eigen::MatrixXd t(s.handle_targets.rows() - 1, d);
              for (Eigen::Index r = 0, w = 0; r < s.handle_targets.rows(); ++r)
                if (r != k) t.row(w++) = s.handle_targets.row(r);
              s.handle_targets = t;
              make_handle_driver();
              return;
            }
          }
          s.drag = Impl::Drag::Pan;
          return;
        }
        if (e.button == 2) {
          s.drag = Impl::Drag::Pan;
          return;
        }
        if (s.direct) {
          const int v = nearest_control_vertex(e.x, e.y, panel);
          if (v >= 0) {
            auto it = std::find(s.handles.begin(), s.handles.end(), v);
            if (it == s.handles.end()) {
              s.handles.push_back(v);
              s.handle_targets.conservativeResize(static_cast<Eigen::Index>(s.handles.size()), d);
              s.handle_targets.row(s.handle_targets.rows() - 1) = pipe.control_positions().row(v);
              make_handle_driver();
              it = s.handles.end() - 1;
            }
            s.dragged_handle = static_cast<int>(it - s.handles.begin());
            s.drag = Impl::Drag::Handle;
            return;
          }
        } else if (sim_driver() && d == 3) {
          Eigen::MatrixXd V;
          pipe.evaluate_with(panels[static_cast<size_t>(panel)], V);
          const std::optional<Hit> hit = cast(ray_at(e.x, e.y, panel), V, F);
          if (hit) {  // the material point under the cursor: rest position -> control element
            Eigen::Vector3d rest = Eigen::Vector3d::Zero();
            for (int k = 0; k < 3; ++k) rest += hit->bary(k) * rest_dense.row(F(hit->face, k)).transpose();
            const interp::Embedding emb = interp::embed(U, T, rest.transpose());
            s.poke_element = emb.element(0);
            s.poke_bary = emb.bary.row(0).transpose();
            double mass = 0;
            const Eigen::VectorXd& masses = sim_driver()->simulator().masses();
            for (int k = 0; k < 4; ++k) mass += masses(T(s.poke_element, k));
            s.poke_k = poke_stiffness(mass, s.opt.poke_response);
            s.poke_plane = hit->point;
            s.poke_target = hit->point;
            release_poke();
            s.poke_handle = sim_driver()->simulator().add_poke(s.poke_element, s.poke_bary, s.poke_target, s.poke_k);
            s.drag = Impl::Drag::Poke;
            return;
          }
        }
        s.drag = d == 2 ? Impl::Drag::Pan : Impl::Drag::Orbit;
        return;
      }
      case Event::Move: {
        const double dx = e.x - s.last_x, dy = e.y - s.last_y;
        s.last_x = e.x, s.last_y = e.y;
        s.mouse_x = e.x, s.mouse_y = e.y;
        if (s.drag == Impl::Drag::Orbit) s.camera.orbit(dx, dy);
        if (s.drag == Impl::Drag::Pan) s.camera.pan(dx, dy, s.window_h());
        if (s.drag == Impl::Drag::Poke && s.poke_handle >= 0 && sim_driver()) {
          s.poke_target = poke_target(ray_at(e.x, e.y, s.panel_of_drag), s.poke_plane, s.camera.direction(), 0.5 * size);
          sim_driver()->simulator().set_poke_target(s.poke_handle, s.poke_target);
        }
        if (s.drag == Impl::Drag::Handle && s.dragged_handle >= 0 &&
            s.dragged_handle < static_cast<int>(s.handles.size())) {
          const Eigen::Index k = s.dragged_handle;
          const Eigen::Vector3d from = pad3(s.handle_targets.row(k));
          const Eigen::Vector3d to = poke_target(ray_at(e.x, e.y, s.panel_of_drag), from, s.camera.direction(), 10 * size);
          s.handle_targets.row(k) = to.head(d).transpose();
          if (auto* hd = dynamic_cast<pipeline::HandleDriver*>(&pipe.driver())) hd->set_targets(s.handle_targets);
        }
        return;
      }
      case Event::Release:
        if (s.drag == Impl::Drag::Poke) release_poke();
        s.drag = Impl::Drag::None;
        s.dragged_handle = -1;
        return;
      case Event::Scroll:
        s.camera.zoom(e.dy);
        return;
      case Event::Key: {
        const std::string& k = e.key;
        if (k == "space") s.opt.playing = !s.opt.playing;
        else if (k == "n") s.step_once = true;
        else if (k == "r") {
          release_poke();
          pipe.reset();
          pipe.step(false);
        } else if (k == "d") set_direct(!s.direct);
        else if (k == "m") {
          const auto& all = pipeline::all_methods();
          auto it = std::find(all.begin(), all.end(), pipe.method());
          pipe.set_method(all[static_cast<size_t>((it - all.begin() + 1) % static_cast<long>(all.size()))]);
          set_panels();
        } else if (k == "s") {
          s.opt.split = !s.opt.split;
          set_panels();
        } else if (k == "w") s.opt.wireframe = !s.opt.wireframe;
        else if (k == "h") s.opt.handles = !s.opt.handles;
        else if (k == "f" || k == "v") reset_view();
        else if (k == "p") {
          char name[64];
          std::snprintf(name, sizeof name, "mbi-screenshot-%04d.png", s.frame);
          s.message = std::string("screenshot: ") + name;
          io::write_png(name, s.last_shot.width > 0 ? s.last_shot : io::Image(1, 1));
        } else if (k == "?") s.help = !s.help;
        else if (k == "q" || k == "escape") s.close = true;
        return;
      }
    }
  };

  // ------------------------------------------------------------------ the loop
  const Eigen::Vector3d color(0.85, 0.62, 0.35);
  while (!glfwWindowShouldClose(s.window) && !s.close) {
    glfwPollEvents();
    while (!s.script.empty() && s.script.front().frame <= s.frame) {
      Event e = s.script.front();
      e.frame = s.frame;
      s.push(e);  // replayed events are recorded too
      s.script.pop_front();
    }
    while (!s.queue.empty()) {
      handle_event(s.queue.front());
      s.queue.pop_front();
    }
    if (per_frame) per_frame(*this);
    if (s.opt.playing || s.step_once || s.direct) {  // direct mode has no time: it follows the handles
      const pipeline::FrameResult r = pipe.step(false);
      if (!r.ok) {
        s.message = "step failed: " + r.message + " (paused; r resets)";
        s.opt.playing = false;
        release_poke();
      }
      s.step_once = false;
    }
    // draw every panel from the GPU evaluator's buffers
    int fbw, fbh;
    glfwGetFramebufferSize(s.window, &fbw, &fbh);
    const auto t_draw = Clock::now();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fbw, fbh);
    glClearColor(1, 1, 1, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    const int n = static_cast<int>(panels.size());
    double gpu_ms = 0;
    const Eigen::MatrixXd X3 = current_X3();
    for (int k = 0; k < n; ++k) {
      const int x0 = fbw * k / n, x1 = fbw * (k + 1) / n;
      glViewport(x0, 0, x1 - x0, fbh);
      gpu_ev->evaluate(pipe.bezier_with(panels[static_cast<size_t>(k)]), d == 3);
      gpu_ms += gpu_ev->timings().upload_ms + gpu_ev->timings().pass_ms;
      const Eigen::Matrix4d vp = s.camera.view_projection(static_cast<double>(x1 - x0) / std::max(fbh, 1));
      if (d == 3)
        s.renderer->draw(*gpu_ev, vp, s.camera.direction(), color, s.opt.wireframe ? &X3 : nullptr,
                         s.opt.wireframe ? &T : nullptr);
      else
        s.renderer->draw_textured(*gpu_ev, vp, *image);
      if (s.opt.handles && s.direct && !s.handles.empty()) {
        Eigen::MatrixXd H(static_cast<Eigen::Index>(s.handles.size()), 3);
        for (size_t h = 0; h < s.handles.size(); ++h) H.row(static_cast<Eigen::Index>(h)) = X3.row(s.handles[h]);
        s.renderer->draw_points(H, vp, {0.1, 0.35, 0.9}, 9.0f);
      }
      if (s.opt.handles && s.direct) s.renderer->draw_points(X3, vp, {0.3, 0.3, 0.3}, 4.0f);
      if (s.poke_handle >= 0) {
        Eigen::MatrixXd P(1, 3);
        P.row(0) = s.poke_target.transpose();
        s.renderer->draw_points(P, vp, {0.85, 0.1, 0.1}, 8.0f);
      }
    }
    glViewport(0, 0, fbw, fbh);
    glFinish();
    s.draw_ms = ms_since(t_draw) - gpu_ms;
    const double dt = ms_since(s.last_frame_time);
    s.last_frame_time = Clock::now();
    s.fps = dt > 0 ? 0.9 * s.fps + 0.1 * 1000.0 / dt : s.fps;

    // panel and HUD
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    if (s.opt.panel) {
      ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_Once);
      ImGui::SetNextWindowBgAlpha(0.85f);
      ImGui::Begin("mbi", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
      const pipeline::FrameTimings& tm = pipe.timings();
      ImGui::Text("%.1f fps   frame %d", s.fps, pipe.frame());
      ImGui::Text("simulation %.2f ms  solve %.2f ms", tm.drive_ms, tm.solve_ms);
      ImGui::Text("interpolation %.2f ms  drawing %.2f ms", gpu_ms, s.draw_ms);
      ImGui::TextDisabled("%s", gpu_ev->name().c_str());
      ImGui::Text("%lld dense vertices, %lld control vertices, %lld elements",
                  static_cast<long long>(pipe.embedding().size()), static_cast<long long>(U.rows()),
                  static_cast<long long>(T.rows()));
      ImGui::Separator();
      if (ImGui::Button(s.opt.playing ? "pause" : "play")) s.opt.playing = !s.opt.playing;
      ImGui::SameLine();
      if (ImGui::Button("step")) s.step_once = true;
      ImGui::SameLine();
      if (ImGui::Button("reset")) {
        release_poke();
        pipe.reset();
        pipe.step(false);
      }
      bool direct = s.direct;
      if (ImGui::Checkbox("direct mode (drag handles)", &direct)) set_direct(direct);
      int method = static_cast<int>(std::find(pipeline::all_methods().begin(), pipeline::all_methods().end(), pipe.method()) -
                                    pipeline::all_methods().begin());
      std::string names;
      for (pipeline::Method m : pipeline::all_methods()) names += std::string(pipeline::method_name(m)) + '\0';
      if (ImGui::Combo("method", &method, names.c_str())) {
        pipe.set_method(pipeline::all_methods()[static_cast<size_t>(method)]);
        set_panels();
      }
      if (ImGui::Checkbox("split view (BI | method)", &s.opt.split)) set_panels();
      ImGui::Checkbox("control wireframe", &s.opt.wireframe);
      ImGui::Checkbox("handle markers", &s.opt.handles);
      float a = static_cast<float>(alpha);
      if (ImGui::SliderFloat("alpha", &a, 0.001f, 1.0f, "%.3f", ImGuiSliderFlags_Logarithmic) && a > 0) {
        alpha = a;
        pipe.set_alpha(alpha);
      }
      if (auto* sd = sim_driver()) {
        sim::Parameters p = sd->simulator().params();
        float dt_s = static_cast<float>(p.dt), md = static_cast<float>(p.mass_damping),
              sdmp = static_cast<float>(p.stiffness_damping);
        float g[3] = {static_cast<float>(p.gravity.x()), static_cast<float>(p.gravity.y()),
                      static_cast<float>(p.gravity.z())};
        bool changed = ImGui::SliderFloat("time step (s)", &dt_s, 1e-4f, 0.1f, "%.4f", ImGuiSliderFlags_Logarithmic);
        changed |= ImGui::SliderInt("substeps", &p.substeps, 1, 16);
        changed |= ImGui::SliderFloat("mass damping (1/s)", &md, 0.0f, 10.0f);
        changed |= ImGui::SliderFloat("stiffness damping (s)", &sdmp, 0.0f, 0.1f);
        changed |= ImGui::InputFloat3("gravity (m/s^2)", g);
        if (changed) {
          p.dt = dt_s, p.mass_damping = md, p.stiffness_damping = sdmp;
          p.gravity = Eigen::Vector3d(g[0], g[1], g[2]);
          try {
            sd->simulator().set_params(p);
          } catch (const std::exception& ex) {
            s.message = ex.what();
          }
        }
        if (rebuild) {
          float E = static_cast<float>(young), nu = static_cast<float>(poisson);
          bool mat = ImGui::SliderFloat("Young's modulus (Pa)", &E, 1e2f, 1e9f, "%.3g", ImGuiSliderFlags_Logarithmic);
          mat |= ImGui::SliderFloat("Poisson ratio", &nu, 0.0f, 0.49f);
          if (mat && ImGui::IsItemDeactivatedAfterEdit()) {}
          if (mat) {
            young = E, poisson = nu;
            release_poke();
            pipe.set_driver(rebuild(young, poisson));
            pipe.reset();
            pipe.step(false);
          }
        }
        float resp = static_cast<float>(s.opt.poke_response);
        if (ImGui::SliderFloat("poke response (s)", &resp, 0.02f, 1.0f, "%.2f")) s.opt.poke_response = resp;
        if (s.poke_handle >= 0) ImGui::Text("poke: stiffness %.3g N/m", s.poke_k);
      }
      if (!s.message.empty()) ImGui::TextWrapped("%s", s.message.c_str());
      ImGui::TextDisabled("? for help");
      const ImVec2 pos = ImGui::GetWindowPos(), sz = ImGui::GetWindowSize();
      s.panel_min = Eigen::Vector2d(pos.x, pos.y);
      s.panel_max = Eigen::Vector2d(pos.x + sz.x, pos.y + sz.y);
      ImGui::End();
    }
    if (s.help) {
      ImGui::SetNextWindowPos(ImVec2(static_cast<float>(s.window_w()) * 0.5f, static_cast<float>(s.window_h()) * 0.5f),
                              ImGuiCond_Always, ImVec2(0.5f, 0.5f));
      ImGui::Begin("help", &s.help, ImGuiWindowFlags_AlwaysAutoResize);
      ImGui::TextUnformatted(kHelp);
      ImGui::End();
    }
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    s.last_shot = read_framebuffer(fbw, fbh);

    // report (tests): the grabbed point, handles, energies, finiteness
    if (!s.opt.report.empty()) {
      nlohmann::json fr;
      fr["frame"] = pipe.frame();
      fr["direct"] = s.direct;
      const Eigen::MatrixXd& X = pipe.control_positions();
      fr["finite"] = X.allFinite();
      fr["timings_ms"] = {{"simulation", pipe.timings().drive_ms}, {"solve", pipe.timings().solve_ms},
                          {"interpolation", gpu_ms}, {"drawing", s.draw_ms}};
      fr["max_displacement"] = (X - U).rowwise().norm().maxCoeff();
      if (auto* sd = sim_driver()) {
        fr["kinetic_energy"] = sd->simulator().kinetic_energy();
        fr["elastic_energy"] = sd->simulator().elastic_energy();
      }
      if (s.poke_handle >= 0) {
        Eigen::Vector3d p = Eigen::Vector3d::Zero();
        for (int k = 0; k < 4; ++k) p += s.poke_bary(k) * pad3(X.row(T(s.poke_element, k)));
        fr["poke"] = {{"point", {p.x(), p.y(), p.z()}},
                      {"target", {s.poke_target.x(), s.poke_target.y(), s.poke_target.z()}},
                      {"stiffness", s.poke_k}};
      }
      nlohmann::json hs = nlohmann::json::array();
      for (size_t h = 0; h < s.handles.size(); ++h) {
        const Eigen::Vector3d pos = pad3(X.row(s.handles[h])), tgt = pad3(s.handle_targets.row(static_cast<Eigen::Index>(h)));
        hs.push_back({{"vertex", s.handles[h]}, {"position", {pos.x(), pos.y(), pos.z()}}, {"target", {tgt.x(), tgt.y(), tgt.z()}}});
      }
      fr["handles"] = hs;
      if (s.report.empty()) {  // where the control vertices are on screen (last panel), for scripts
        const int np = static_cast<int>(panels.size());
        const double pw = static_cast<double>(s.window_w()) / np;
        nlohmann::json cs = nlohmann::json::array();
        for (Eigen::Index i = 0; i < X3.rows(); ++i) {
          const Eigen::Vector2d q = s.camera.project(X3.row(i).transpose(), static_cast<int>(std::lround(pw)), s.window_h());
          cs.push_back({q.x() + (np - 1) * pw, q.y()});
        }
        fr["control_window"] = cs;
      }
      s.report.push_back(fr);
    }
    glfwSwapBuffers(s.window);
    ++s.frame;
    if (s.opt.frames > 0 && s.frame >= s.opt.frames) break;
  }
  if (!s.opt.screenshot.empty()) io::write_png(s.opt.screenshot, s.last_shot);
  if (!s.opt.report.empty()) io::write_text_atomic(s.opt.report, s.report.dump(1) + "\n");
  return 0;
}

}  // namespace mbi::viewer
