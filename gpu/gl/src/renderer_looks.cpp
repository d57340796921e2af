// The viewer's looks drawn by the Renderer: the ground under the model and the surface in the
// clay material (gpu/gl/shaders/ground.*, material.*), their programs made on first use.
#include <mbi/gpu/renderer.hpp>

#include <mbi/gpu/program.hpp>

#include "gl_util.hpp"

#include <cmath>
#include <sstream>
#include <string>
#include <utility>

namespace mbi::gpu {
namespace {

void uniform3(GLuint p, const char* name, const Eigen::Vector3d& v) {
  glUniform3f(glGetUniformLocation(p, name), static_cast<float>(v.x()), static_cast<float>(v.y()),
              static_cast<float>(v.z()));
}

void uniform2(GLuint p, const char* name, const Eigen::Vector2d& v) {
  glUniform2f(glGetUniformLocation(p, name), static_cast<float>(v.x()), static_cast<float>(v.y()));
}

// Throws Error naming the first field of `g` the shader cannot draw.
void check_ground(const Ground& g) {
  auto fail = [](const std::string& what) { throw Error("Renderer::draw_ground: " + what); };
  const std::pair<const char*, bool> finite[] = {
      {"center", g.center.allFinite()}, {"e1", g.e1.allFinite()}, {"e2", g.e2.allFinite()},
      {"shadow_center", g.shadow_center.allFinite()}, {"shadow_half", g.shadow_half.allFinite()},
      {"background", g.background.allFinite()}};
  for (const auto& [name, ok] : finite)
    if (!ok) fail(std::string(name) + " is not finite");
  const std::pair<const char*, double> positive[] = {
      {"half", g.half}, {"spacing", g.spacing}, {"shadow_soft", g.shadow_soft}};
  for (const auto& [name, v] : positive)
    if (!(v > 0) || !std::isfinite(v)) {
      std::ostringstream text;
      text << name << " must be positive and finite, not " << v;
      fail(text.str());
    }
  if (g.shadow_half.minCoeff() < 0) fail("shadow_half must not be negative");
  if (std::abs(g.e1.norm() - 1) > 1e-6 || std::abs(g.e2.norm() - 1) > 1e-6) fail("e1 and e2 must be unit vectors");
}

}  // namespace

void Renderer::draw_ground(const Ground& g, const Eigen::Matrix4d& view_projection) {
  check_ground(g);
  if (!ground_program_) {
    ground_program_ = program("ground", shaders::ground);
    glGenVertexArrays(1, &ground_vao_);
    glGenBuffers(1, &ground_corners_);
    const float corners[8] = {-1, -1, 1, -1, -1, 1, 1, 1};
    glBindVertexArray(ground_vao_);
    glBindBuffer(GL_ARRAY_BUFFER, ground_corners_);
    glBufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
    glBindVertexArray(0);
  }
  const Eigen::Matrix4f vp = view_projection.cast<float>();
  const GLuint p = ground_program_;
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(p);
  glUniformMatrix4fv(glGetUniformLocation(p, "view_projection"), 1, GL_FALSE, vp.data());
  uniform3(p, "center", g.center);
  uniform3(p, "e1", g.e1);
  uniform3(p, "e2", g.e2);
  uniform3(p, "background", g.background);
  glUniform1f(glGetUniformLocation(p, "half_side"), static_cast<float>(g.half));
  glUniform1f(glGetUniformLocation(p, "spacing"), static_cast<float>(g.spacing));
  glUniform1f(glGetUniformLocation(p, "soft"), static_cast<float>(g.shadow_soft));
  uniform2(p, "shadow_center", g.shadow_center);
  uniform2(p, "shadow_half", g.shadow_half);
  glBindVertexArray(ground_vao_);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  glBindVertexArray(0);
  glUseProgram(0);
  detail::check("Renderer::draw_ground");
}

void Renderer::draw_material(const GpuEvaluator& ev, const Eigen::Matrix4d& view_projection,
                             const Eigen::Matrix3d& view_rotation, const Eigen::Vector3d& color) {
  if (ev.dim() != 3 || !ev.has_normals()) throw Error("Renderer: needs a 3D evaluation with normals");
  if (!material_program_) material_program_ = program("surface material", shaders::material);
  const Eigen::Matrix4f vp = relative_to(view_projection, ev.origin());
  const Eigen::Matrix3f rotation = view_rotation.cast<float>();
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(material_program_);
  glUniformMatrix4fv(glGetUniformLocation(material_program_, "view_projection"), 1, GL_FALSE, vp.data());
  glUniformMatrix3fv(glGetUniformLocation(material_program_, "view_rotation"), 1, GL_FALSE, rotation.data());
  uniform3(material_program_, "color", color);
  surface_.draw(ev, {.offset = 0.5f});  // in front of draw()'s surface (offset 1)
  glUseProgram(0);
  detail::check("Renderer::draw_material");
}

}  // namespace mbi::gpu
