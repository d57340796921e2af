#include "panel.hpp"

#include "crease_layer.hpp"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>

namespace mbi::viewer {
namespace {

const char* kHelp =
    "Mouse (left button):\n"
    "  on the model      poke: grab the surface, a spring pulls it to the cursor\n"
    "  on a collider     drag it: it follows the cursor and pushes the model\n"
    "  direct mode       click a control vertex: it becomes a handle; drag it\n"
    "  on the background orbit (2D: pan)\n"
    "  right drag        pan; right click on a handle removes it\n"
    "  wheel / pinch     zoom\n"
    "  drop a model file on the window to view it\n"
    "Keys:\n"
    "  space  play / pause      n  one step        r  reset\n"
    "  d      direct mode on/off (drag handles, no physics)\n"
    "  t      contact on/off (surface contact scenes)\n"
    "  m      next method       s  split view (BI | method)\n"
    "  w      control wireframe h  handle markers\n"
    "  g      creases in colour (the gradient jump at the control faces)\n"
    "  c      fold / unfold the panel\n"
    "  f      frame the model   p  screenshot (mbi-screenshot-NNNN.png)\n"
    "  o      video: start / stop (mbi-video-NNNN.mp4; --video: pause)\n"
    "  [ / ]  alpha / 2, alpha x 2 (0.001 to 1)\n"
    "  ?      this help         q / escape  quit";

void statistics(const Stage& stage, const FrameTimes& times) {
  const pipeline::FrameTimings& tm = stage.pipe.timings();
  ImGui::Text("%.1f fps   frame %d", times.fps, stage.pipe.frame());
  ImGui::Text("simulation %.2f ms  solve %.2f ms", tm.drive_ms, tm.solve_ms);
  ImGui::Text("interpolation %.2f ms  drawing %.2f ms", times.interpolation_ms, times.drawing_ms);
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled));
  ImGui::TextWrapped("%s (%s)", stage.evaluator.name().c_str(), stage.evaluator_why.c_str());
  ImGui::TextWrapped("looks: %s", stage.looks.c_str());
  ImGui::PopStyleColor();
  ImGui::TextWrapped("%lld dense vertices, %lld control vertices, %lld elements",
              static_cast<long long>(stage.pipe.embedding().size()), static_cast<long long>(stage.U.rows()),
              static_cast<long long>(stage.T.rows()));
}

void playback(Interaction& in, ViewerOptions& options, Controls& controls) {
  if (ImGui::Button(options.playing ? "pause" : "play")) options.playing = !options.playing;
  ImGui::SameLine();
  if (ImGui::Button("step")) controls.step_once = true;
  ImGui::SameLine();
  if (ImGui::Button("reset")) in.reset();
  bool direct = in.direct();
  if (ImGui::Checkbox("direct mode (drag handles)", &direct)) in.set_direct(direct);
}

void view_switches(Stage& stage, ViewerOptions& options) {
  const std::vector<pipeline::Method>& all = pipeline::all_methods();
  int method = static_cast<int>(std::find(all.begin(), all.end(), stage.pipe.method()) - all.begin());
  std::string names;
  for (pipeline::Method m : all) names += std::string(pipeline::method_name(m)) + '\0';
  if (ImGui::Combo("method", &method, names.c_str())) stage.set_method(all[static_cast<size_t>(method)], options.split);
  if (ImGui::Checkbox("split view (BI | method)", &options.split)) stage.set_views(options.split);
  ImGui::Checkbox("control wireframe", &options.wireframe);
  if (stage.d == 3) ImGui::Checkbox("creases in colour (g)", &options.creases);
  ImGui::Checkbox("handle markers", &options.handles);
  float a = static_cast<float>(stage.alpha);
  if (ImGui::SliderFloat("alpha", &a, static_cast<float>(Stage::kMinAlpha), static_cast<float>(Stage::kMaxAlpha), "%.3f",
                         ImGuiSliderFlags_Logarithmic))
    stage.set_alpha(a);
}

// Time stepping, damping and gravity: the running simulation takes them at once.
void simulation_parameters(pipeline::SimulatorDriver& sd, Controls& controls) {
  sim::Parameters p = sd.simulator().params();
  float dt = static_cast<float>(p.dt), md = static_cast<float>(p.mass_damping),
        sdmp = static_cast<float>(p.stiffness_damping);
  float g[3] = {static_cast<float>(p.gravity.x()), static_cast<float>(p.gravity.y()),
                static_cast<float>(p.gravity.z())};
  bool changed = ImGui::SliderFloat("time step (s)", &dt, 1e-4f, 0.1f, "%.4f", ImGuiSliderFlags_Logarithmic);
  changed |= ImGui::SliderInt("substeps", &p.substeps, 1, 16);
  changed |= ImGui::SliderFloat("mass damping (1/s)", &md, 0.0f, 10.0f);
  changed |= ImGui::SliderFloat("stiffness damping (s)", &sdmp, 0.0f, 0.1f);
  changed |= ImGui::InputFloat3("gravity (m/s^2)", g);
  if (!changed) return;
  p.dt = dt, p.mass_damping = md, p.stiffness_damping = sdmp;
  p.gravity = Eigen::Vector3d(g[0], g[1], g[2]);
  try {
    sd.simulator().set_params(p);
  } catch (const std::exception& ex) {
    controls.message = ex.what();
  }
}

// Young's modulus and Poisson ratio: a new simulation, restarted.
void material(Stage& stage, Interaction& in) {
  float E = static_cast<float>(stage.material.youngs_modulus), nu = static_cast<float>(stage.material.poisson_ratio);
  bool changed = ImGui::SliderFloat("Young's modulus (Pa)", &E, 1e2f, 1e9f, "%.3g", ImGuiSliderFlags_Logarithmic);
  changed |= ImGui::SliderFloat("Poisson ratio", &nu, 0.0f, 0.49f);
  if (!changed) return;
  stage.material.youngs_modulus = E, stage.material.poisson_ratio = nu;
  in.release_poke();
  stage.pipe.set_driver(stage.rebuild(stage.material));
  in.reset();
}

// Surface contact on or off, the points touching a collider; the colliders are dragged in the views.
void contact(Stage& stage, const pipeline::SimulatorDriver& sd) {
  const pipeline::SurfaceContact* c = stage.contact();
  if (!c) return;
  bool on = stage.contact_on();
  if (ImGui::Checkbox("contact (t)", &on)) stage.set_contact(on);
  ImGui::Text("touching: %d of %lld points", sd.touching_points(), c->contact_points());
  ImGui::TextDisabled("colliders: %zu (drag one to push)", c->colliders().size());
}

void simulation(Stage& stage, Interaction& in, ViewerOptions& options, Controls& controls) {
  pipeline::SimulatorDriver* sd = stage.simulation();
  if (!sd) return;
  simulation_parameters(*sd, controls);
  if (stage.rebuild) material(stage, in);
  float response = static_cast<float>(options.poke_response);
  if (ImGui::SliderFloat("poke response (s)", &response, 0.02f, 1.0f, "%.2f")) options.poke_response = response;
  if (in.poke().handle >= 0) ImGui::Text("poke: stiffness %.3g N/m", in.poke().stiffness);
  contact(stage, *sd);
}

// Docked at the left edge, the layout's width and the window's height; its arrow folds it.
void panel(Stage& stage, Interaction& in, ViewerOptions& options, Controls& controls, const FrameTimes& times) {
  const Rect& r = stage.layout.panel;
  ImGui::SetNextWindowPos(ImVec2(static_cast<float>(r.x), static_cast<float>(r.y)), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(static_cast<float>(r.w), static_cast<float>(r.h)), ImGuiCond_Always);
  if (controls.toggle_collapse) ImGui::SetNextWindowCollapsed(!controls.collapsed, ImGuiCond_Always);
  controls.toggle_collapse = false;
  const bool open = ImGui::Begin("mbi", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize);
  controls.collapsed = ImGui::IsWindowCollapsed();
  in.panel_min = Eigen::Vector2d(r.x, r.y);
  in.panel_max = Eigen::Vector2d(r.x + r.w, r.y + r.h);
  if (!open) {
    ImGui::End();
    return;
  }
  ImGui::PushItemWidth(-ImGui::GetFontSize() * 11);  // room for the labels
  statistics(stage, times);
  ImGui::Separator();
  playback(in, options, controls);
  view_switches(stage, options);
  simulation(stage, in, options, controls);
  if (!controls.message.empty()) ImGui::TextWrapped("%s", controls.message.c_str());
  ImGui::TextDisabled("? for help, c folds this panel");
  ImGui::PopItemWidth();
  ImGui::End();
}

// Each view's method, at its top-left corner.
void labels(const Stage& stage) {
  ImDrawList* list = ImGui::GetForegroundDrawList();
  for (size_t k = 0; k < stage.layout.views.size() && k < stage.views.size(); ++k) {
    const Rect& r = stage.layout.views[k];
    list->AddText(ImVec2(static_cast<float>(r.x + 10), static_cast<float>(r.y + 8)), IM_COL32(30, 30, 30, 255),
                  pipeline::method_name(stage.views[k]));
  }
}

ImU32 scale_color(double t) {
  const Eigen::Vector3d c = pipeline::crease_color(t);
  return IM_COL32(static_cast<int>(c(0) * 255 + 0.5), static_cast<int>(c(1) * 255 + 0.5), static_cast<int>(c(2) * 255 + 0.5), 255);
}

// The crease colours' legend at the views' bottom-left: what they show, the bar, its ends' values.
void crease_legend(CreaseLayer& creases, const Layout& layout) {
  const Rect& first = layout.views.front();
  const float span = static_cast<float>(layout.views.back().x + layout.views.back().w - first.x);
  const float w = std::min(360.0f, span - 32), x = static_cast<float>(first.x) + 16;
  const float y = static_cast<float>(first.y + first.h) - 64, bar = y + 20;
  ImDrawList* list = ImGui::GetForegroundDrawList();
  list->AddRectFilled(ImVec2(x - 8, y - 6), ImVec2(x + w + 8, y + 58), IM_COL32(255, 255, 255, 220), 4.0f);
  list->AddText(ImVec2(x, y), IM_COL32(30, 30, 30, 255), pipeline::kCreaseQuantity);
  const int segments = 32;
  for (int s = 0; s < segments; ++s) {
    const float a = x + w * static_cast<float>(s) / segments, b = x + w * static_cast<float>(s + 1) / segments;
    list->AddRectFilledMultiColor(ImVec2(a, bar), ImVec2(b, bar + 14), scale_color(double(s) / segments),
                                  scale_color(double(s + 1) / segments), scale_color(double(s + 1) / segments),
                                  scale_color(double(s) / segments));
  }
  const std::string top = pipeline::crease_number(pipeline::crease_scale(creases.top()));
  list->AddText(ImVec2(x, bar + 17), IM_COL32(30, 30, 30, 255), "0");
  list->AddText(ImVec2(x + w - ImGui::CalcTextSize(top.c_str()).x, bar + 17), IM_COL32(30, 30, 30, 255), top.c_str());
  creases.legend = {x, bar, w, 14};
}

void help(bool& open, const WindowSize& window) {
  ImGui::SetNextWindowPos(ImVec2(static_cast<float>(window.width) * 0.5f, static_cast<float>(window.height) * 0.5f),
                          ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::Begin("help", &open, ImGuiWindowFlags_AlwaysAutoResize);
  ImGui::TextUnformatted(kHelp);
  ImGui::End();
}

}  // namespace

void draw_gui(Stage& stage, Interaction& in, ViewerOptions& options, Controls& controls, const FrameTimes& times,
              const WindowSize& window) {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  if (options.panel) panel(stage, in, options, controls, times);
  labels(stage);
  if (options.creases && stage.creases) crease_legend(*stage.creases, stage.layout);
  if (controls.help) help(controls.help, window);
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace mbi::viewer
