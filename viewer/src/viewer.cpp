#include <mbi/viewer/viewer.hpp>

#include "draw.hpp"
#include "evaluation.hpp"
#include "interaction.hpp"
#include "panel.hpp"
#include "recordings.hpp"
#include "session_io.hpp"

#include <mbi/gpu/window.hpp>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <mbi/scenes/evaluator.hpp>

#include <algorithm>
#include <cstdio>

namespace mbi::viewer {
namespace {

const char* key_name(int key) {
  switch (key) {
    case GLFW_KEY_SPACE: return "space";
    case GLFW_KEY_ESCAPE: return "escape";
    case GLFW_KEY_SLASH: return "?";
    case GLFW_KEY_LEFT_BRACKET: return "[";
    case GLFW_KEY_RIGHT_BRACKET: return "]";
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

GLFWwindow* open_window(const ViewerOptions& options, int samples) {
  if (!glfwInit()) {
    const char* why = nullptr;
    glfwGetError(&why);
    throw Error(std::string("no display: cannot open a window (") + (why ? why : "GLFW failed") + ")");
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, samples);
  GLFWwindow* window = glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
  if (!window) {
    const char* why = nullptr;
    glfwGetError(&why);
    glfwTerminate();
    throw Error(std::string("no OpenGL 3.3 window: ") + (why ? why : "GLFW failed"));
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(options.frames > 0 ? 0 : 1);
  return window;
}

// The looks `asked` for on this OpenGL renderer: Auto is Software on a software renderer.
Looks resolve_looks(Looks asked) {
  if (asked != Looks::Auto) return asked;
  const std::string renderer = gpu::renderer_name();
  const bool software = renderer.find("llvmpipe") != std::string::npos || renderer.find("softpipe") != std::string::npos;
  return software ? Looks::Software : Looks::Full;
}

// The window for the looks: MSAA only in the full looks. Auto learns the renderer from a first
// window, and opens another without MSAA on a software renderer (where it costs the frame rate).
GLFWwindow* open_window_for_looks(const ViewerOptions& options, Looks& looks) {
  const bool msaa_maybe = options.looks == Looks::Auto || options.looks == Looks::Full;
  GLFWwindow* window = open_window(options, msaa_maybe ? 4 : 0);
  looks = resolve_looks(options.looks);
  if (msaa_maybe && looks != Looks::Full) {
    glfwDestroyWindow(window);
    window = open_window(options, 0);
  }
  return window;
}

}  // namespace

// The window and what lasts between frames. The GLFW callbacks turn input into events; the frame
// loop (show) handles them, so scripted and live input take the same path.
struct Viewer::Impl {
  ViewerOptions opt;
  GLFWwindow* window = nullptr;
  std::shared_ptr<gpu::Context> context;
  std::string evaluator_why;  ///< why options.gpu chose the evaluator (the HUD)
  std::unique_ptr<gpu::Renderer> renderer;
  Looks looks = Looks::Plain;         ///< resolved: never Auto
  std::unique_ptr<Recordings> videos;
  std::filesystem::path dropped;      ///< a model dropped on the window: show() returns for it
  Camera camera;
  int frame = 0;
  std::unique_ptr<SessionFiles> files;
  Inputs inputs;
  Controls controls;
  FrameTimes times;
  io::Image last_shot;
  const Interaction* interaction = nullptr;  ///< while showing: only drags' moves are events

  static Impl& of(GLFWwindow* w) { return *static_cast<Impl*>(glfwGetWindowUserPointer(w)); }
  Event event(Event::Kind kind) const {
    Event e;
    e.frame = frame;
    e.kind = kind;
    return e;
  }
  static void on_mouse_button(GLFWwindow* w, int button, int action, int) {
    if (ImGui::GetIO().WantCaptureMouse && action == GLFW_PRESS) return;
    Event e = of(w).event(action == GLFW_PRESS ? Event::Press : Event::Release);
    glfwGetCursorPos(w, &e.x, &e.y);
    e.button = button;
    of(w).inputs.push(e);
  }
  static void on_cursor(GLFWwindow* w, double x, double y) {
    Impl& s = of(w);
    if (!s.interaction || !s.interaction->dragging()) return;  // only drags matter (and keep recordings short)
    Event e = s.event(Event::Move);
    e.x = x, e.y = y;
    s.inputs.push(e);
  }
  static void on_scroll(GLFWwindow* w, double, double dy) {
    if (ImGui::GetIO().WantCaptureMouse) return;
    Event e = of(w).event(Event::Scroll);
    e.dy = dy;
    of(w).inputs.push(e);
  }
  static void on_drop(GLFWwindow* w, int count, const char** paths) {
    if (count < 1) return;  // one model at a time: the first
    Event e = of(w).event(Event::Drop);
    e.path = paths[0];
    of(w).inputs.push(e);
  }
  static void on_key(GLFWwindow* w, int key, int, int action, int mods) {
    if (action != GLFW_PRESS || ImGui::GetIO().WantCaptureKeyboard) return;
    const char* name = key == GLFW_KEY_SLASH && (mods & GLFW_MOD_SHIFT) ? "?" : key_name(key);
    if (!name) return;
    Event e = of(w).event(Event::Key);
    e.key = name;
    of(w).inputs.push(e);
  }

  WindowSize window_size() const {
    int w, h;
    glfwGetWindowSize(window, &w, &h);
    return {std::max(w, 1), std::max(h, 1)};
  }

  // The panel and the views for this window size and the views shown
  void lay_out(Stage& stage) const {
    const WindowSize w = window_size();
    int fbw, fbh;
    glfwGetFramebufferSize(window, &fbw, &fbh);
    stage.layout = make_layout(w.width, w.height, std::max(fbw, 1), std::max(fbh, 1), static_cast<int>(stage.views.size()),
                               opt.panel, controls.collapsed);
  }
  void handle(const Event& e, Stage& stage, Interaction& in);
  void key(const std::string& k, Stage& stage, Interaction& in);
  void snapshot();
  void advance(Stage& stage, Interaction& in);
  Eigen::MatrixXd draw(Stage& stage, Interaction& in, bool keep);
  void finish();
};

Viewer::Viewer(const ViewerOptions& options) : Viewer(options, std::make_unique<SessionFiles>(options)) {}

Viewer::Viewer(const ViewerOptions& options, std::unique_ptr<SessionFiles> files) : impl_(std::make_unique<Impl>()) {
  impl_->opt = options;
  impl_->files = std::move(files);
  impl_->inputs.open(*impl_->files);
  impl_->window = open_window_for_looks(options, impl_->looks);
  impl_->context = gpu::Context::adopt_current();
  impl_->renderer = std::make_unique<gpu::Renderer>(*impl_->context);
  impl_->videos = std::make_unique<Recordings>(*impl_->files);
  glfwSetWindowUserPointer(impl_->window, impl_.get());
  glfwSetMouseButtonCallback(impl_->window, &Impl::on_mouse_button);
  glfwSetCursorPosCallback(impl_->window, &Impl::on_cursor);
  glfwSetScrollCallback(impl_->window, &Impl::on_scroll);
  glfwSetKeyCallback(impl_->window, &Impl::on_key);
  glfwSetDropCallback(impl_->window, &Impl::on_drop);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui_ImplGlfw_InitForOpenGL(impl_->window, true);  // chains to the callbacks above
  ImGui_ImplOpenGL3_Init("#version 330 core");
}

Viewer::~Viewer() {
  if (!impl_ || !impl_->window) return;
  impl_->videos.reset();  // stops an unfinished ffmpeg
  impl_->renderer.reset();
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(impl_->window);
  glfwTerminate();
}

std::unique_ptr<pipeline::Evaluator> Viewer::evaluator() {
  const EvaluatorChoice choice = choose_evaluator(impl_->opt.gpu, impl_->context->renderer());
  impl_->evaluator_why = choice.why;
  // on the CPU the float kernels: the picture needs no more, and they are several times faster
  scenes::Evaluation e =
      scenes::make_evaluator(choice.use, [](const std::string&) {}, impl_->context, pipeline::Precision::Float);
  if (e.context) return std::move(e.evaluator);
  return std::make_unique<DrawnEvaluator>(std::move(e.evaluator), std::make_unique<gpu::GpuEvaluator>(*impl_->context));
}

int Viewer::frame() const { return impl_->frame; }
std::filesystem::path Viewer::dropped() const { return impl_->dropped; }
void Viewer::say(const std::string& message) {
  impl_->controls.message = message;
  std::fprintf(stderr, "mbi view: %s\n", message.c_str());
}
ViewerOptions& Viewer::options() { return impl_->opt; }

io::Image Viewer::screenshot() { return impl_->last_shot; }

void Viewer::Impl::handle(const Event& e, Stage& stage, Interaction& in) {
  switch (e.kind) {
    case Event::Press: in.press(e.x, e.y, e.button, window_size()); return;
    case Event::Move: in.move(e.x, e.y, window_size()); return;
    case Event::Release: in.release(); return;
    case Event::Scroll: in.scroll(e.dy); return;
    case Event::Key: key(e.key, stage, in); return;
    case Event::Drop:
      if (opt.accept_drops) dropped = e.path;
      else controls.message = "a dropped file is not taken here: " + e.path;
      return;
  }
}

void Viewer::Impl::key(const std::string& k, Stage& stage, Interaction& in) {
  if (k == "space") opt.playing = !opt.playing;
  else if (k == "n") controls.step_once = true;
  else if (k == "r") in.reset();
  else if (k == "d") in.set_direct(!in.direct());
  else if (k == "t") stage.set_contact(!stage.contact_on());
  else if (k == "m") {
    const auto& all = pipeline::all_methods();
    auto it = std::find(all.begin(), all.end(), stage.pipe.method());
    stage.set_method(all[static_cast<size_t>((it - all.begin() + 1) % static_cast<long>(all.size()))], opt.split);
  } else if (k == "s") {
    opt.split = !opt.split;
    stage.set_views(opt.split);
  } else if (k == "c") controls.toggle_collapse = true;
  else if (k == "w") opt.wireframe = !opt.wireframe;
  else if (k == "g") opt.creases = !opt.creases;
  else if (k == "h") opt.handles = !opt.handles;
  else if (k == "f" || k == "v") stage.frame(camera, opt.up);
  else if (k == "[" || k == "]") stage.set_alpha(stage.alpha * (k == "[" ? 0.5 : 2.0));
  else if (k == "p") controls.snapshot = true;
  else if (k == "o") {
    int fbw, fbh;
    glfwGetFramebufferSize(window, &fbw, &fbh);
    controls.message = videos->toggle(frame, fbw, fbh);
  }
  else if (k == "?") controls.help = !controls.help;
  else if (k == "q" || k == "escape") controls.close = true;
}

// The p key: a screenshot of this frame; one that cannot be written is said (panel, stderr,
// report), and the session goes on.
void Viewer::Impl::snapshot() {
  controls.snapshot = false;
  char name[64];
  std::snprintf(name, sizeof name, "mbi-screenshot-%04d.png", frame);
  try {
    files->snapshot(name, last_shot.width > 0 ? last_shot : io::Image(1, 1));
    controls.message = std::string("screenshot: ") + name;
  } catch (const std::exception& e) {
    controls.message = std::string("screenshot not written: ") + e.what();
    std::fprintf(stderr, "mbi view: %s\n", controls.message.c_str());
  }
}

// One step when playing or asked to; direct mode has no time: it follows the handles every frame.
// A dragged collider moves to the cursor within the step (at once when paused).
void Viewer::Impl::advance(Stage& stage, Interaction& in) {
  const bool stepping = opt.playing || controls.step_once || in.direct();
  const pipeline::SimulatorDriver* sd = stage.simulation();
  in.carry_collider(stepping && sd ? sd->simulator().params().dt : 0.0);
  if (!stepping) return;
  const pipeline::FrameResult r = stage.pipe.step(false);
  if (!r.ok) {
    controls.message = "step failed: " + r.message + " (paused; r resets)";
    opt.playing = false;
    in.release();
  }
  controls.step_once = false;
}

// The views, then the panel over them; keeps the picture when something will want it (reading
// it back stalls a software renderer for milliseconds). Returns the drawn control positions.
Eigen::MatrixXd Viewer::Impl::draw(Stage& stage, Interaction& in, bool keep) {
  int fbw, fbh;
  glfwGetFramebufferSize(window, &fbw, &fbh);
  Eigen::MatrixXd X3 = stage.control_positions_3d();
  lay_out(stage);
  draw_views(*renderer, stage, in, camera, opt, X3, fbw, fbh, times, looks != Looks::Plain);
  draw_gui(stage, in, opt, controls, times, window_size());
  videos->add_frame(controls.message);
  if (keep || controls.snapshot) last_shot = gpu::read_window(fbw, fbh);
  if (controls.snapshot) snapshot();
  return X3;
}

void Viewer::Impl::finish() {
  videos->finish();  // --video's ffmpeg must succeed before any output moves into place
  files->finish(last_shot);
}

void Viewer::show(const Shown& shown) {
  Impl& s = *impl_;
  Stage stage(shown);
  stage.evaluator_why = s.evaluator_why;
  stage.looks = kLooksNames.name(s.looks);
  s.renderer->set_faces(shown.faces);
  s.dropped.clear();
  if (s.frame == 0) {
    int fbw, fbh;
    glfwGetFramebufferSize(s.window, &fbw, &fbh);
    s.videos->start(s.opt.video, fbw, fbh);
  }
  stage.frame(s.camera, s.opt.up);
  stage.set_views(s.opt.split);
  Interaction in(stage, s.camera, s.opt);
  s.interaction = &in;
  struct Forget {
    Impl& s;
    ~Forget() { s.interaction = nullptr; }
  } forget{s};
  stage.pipe.step(false);  // frame 0
  while (!glfwWindowShouldClose(s.window) && !s.controls.close) {
    glfwPollEvents();
    s.lay_out(stage);
    for (const Event& e : s.inputs.take(s.frame)) s.handle(e, stage, in);
    if (!s.dropped.empty()) return;  // the caller loads it and shows it: no files written yet
    if (shown.per_frame) shown.per_frame(*this);
    s.advance(stage, in);
    // kept for --screenshot and for a caller's per_frame (Viewer::screenshot())
    const Eigen::MatrixXd X3 = s.draw(stage, in, s.files->screenshot_at_end() || shown.per_frame);
    if (s.files->reporting()) {
      nlohmann::json fr = frame_report(stage, in, s.times, X3, s.camera, s.window_size(), s.frame == 0);
      if (!s.controls.message.empty()) fr["message"] = s.controls.message;
      s.files->report(fr);
    }
    s.files->check();
    glfwSwapBuffers(s.window);
    ++s.frame;
    if (s.opt.frames > 0 && s.frame >= s.opt.frames) break;
  }
  s.finish();
}

}  // namespace mbi::viewer
