#include "scenery.hpp"

#include <mbi/gpu/program.hpp>

#include <epoxy/gl.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

namespace mbi::viewer {
namespace {

void uniform3(GLuint p, const char* name, const Eigen::Vector3d& v) {
  glUniform3f(glGetUniformLocation(p, name), static_cast<float>(v.x()), static_cast<float>(v.y()),
              static_cast<float>(v.z()));
}

// The extent of the points Y (rows) along e1 and e2.
void footprint(const Eigen::MatrixXd& Y, const Ground& g, Eigen::Vector2d& lo, Eigen::Vector2d& hi) {
  const Eigen::VectorXd a = Y * g.e1, b = Y * g.e2;
  lo = {a.minCoeff(), b.minCoeff()};
  hi = {a.maxCoeff(), b.maxCoeff()};
}

}  // namespace

Ground ground_at_rest(const Eigen::MatrixXd& U, const Eigen::MatrixXd& P, const Eigen::Vector3d& up_in) {
  Ground g;
  const Eigen::Vector3d up = up_in.normalized();
  const Eigen::Vector3d side = std::abs(up.x()) < 0.9 ? Eigen::Vector3d(Eigen::Vector3d::UnitX()) : Eigen::Vector3d(Eigen::Vector3d::UnitY());
  g.e1 = side.cross(up).normalized();
  g.e2 = up.cross(g.e1);
  Eigen::Vector2d cage_lo, cage_hi, model_lo, model_hi;
  footprint(U, g, cage_lo, cage_hi);
  footprint(P, g, model_lo, model_hi);
  const double size = std::max((P.colwise().maxCoeff() - P.colwise().minCoeff()).norm(), 1e-9);
  g.mid = 0.5 * (model_lo + model_hi);
  // the model stands on the ground (its lowest point, a hair lower: no flicker where it touches)
  g.center = ((P * up).minCoeff() - 2e-3 * size) * up + g.mid.x() * g.e1 + g.mid.y() * g.e2;
  g.half = 1.5 * size;
  g.spacing = std::pow(10.0, std::floor(std::log10(size / 4)));
  g.margin = 0.5 * ((cage_hi - cage_lo) - (model_hi - model_lo)).cwiseMax(0.0);
  g.shadow_soft = 0.1 * size;
  return g;
}

void cast_shadow(Ground& g, const Eigen::MatrixXd& X) {
  // the control mesh's footprint less its margin around the model, a little inside (the fade
  // adds the rest)
  Eigen::Vector2d lo, hi;
  footprint(X, g, lo, hi);
  g.shadow_center = 0.5 * (lo + hi) - g.mid;
  g.shadow_half = (0.5 * (hi - lo) - g.margin - Eigen::Vector2d::Constant(0.25 * g.shadow_soft)).cwiseMax(0.0);
}

Scenery::Scenery() {
  surface_ = gpu::program("surface material", gpu::shaders::material);
  ground_ = gpu::program("ground", gpu::shaders::ground);
  glGenVertexArrays(1, &ground_vao_);
  glGenBuffers(1, &corners_);
  const float corners[8] = {-1, -1, 1, -1, -1, 1, 1, 1};
  glBindVertexArray(ground_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, corners_);
  glBufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindVertexArray(0);
}

Scenery::~Scenery() {
  glDeleteBuffers(1, &corners_);
  glDeleteVertexArrays(1, &ground_vao_);
  glDeleteProgram(surface_);
  glDeleteProgram(ground_);
}

void Scenery::set_faces(const Eigen::MatrixXi& F) { mesh_.set_faces(F); }

void Scenery::draw_ground(const Ground& g, const Eigen::Matrix4d& view_projection) {
  const Eigen::Matrix4f vp = view_projection.cast<float>();
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(ground_);
  glUniformMatrix4fv(glGetUniformLocation(ground_, "view_projection"), 1, GL_FALSE, vp.data());
  uniform3(ground_, "center", g.center);
  uniform3(ground_, "e1", g.e1);
  uniform3(ground_, "e2", g.e2);
  uniform3(ground_, "background", {kBackground[0], kBackground[1], kBackground[2]});
  glUniform1f(glGetUniformLocation(ground_, "half_side"), static_cast<float>(g.half));
  glUniform1f(glGetUniformLocation(ground_, "spacing"), static_cast<float>(g.spacing));
  glUniform1f(glGetUniformLocation(ground_, "soft"), static_cast<float>(g.shadow_soft));
  glUniform2f(glGetUniformLocation(ground_, "shadow_center"), static_cast<float>(g.shadow_center.x()),
              static_cast<float>(g.shadow_center.y()));
  glUniform2f(glGetUniformLocation(ground_, "shadow_half"), static_cast<float>(g.shadow_half.x()),
              static_cast<float>(g.shadow_half.y()));
  glBindVertexArray(ground_vao_);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  glBindVertexArray(0);
  glUseProgram(0);
}

void Scenery::draw_surface(const gpu::GpuEvaluator& ev, const Eigen::Matrix4d& view_projection, const Camera& camera,
                           const Eigen::Vector3d& color) {
  Eigen::Matrix3f rotation;  // world -> camera (x right, y up, z toward the eye)
  rotation.row(0) = camera.right().cast<float>().transpose();
  rotation.row(1) = camera.up().cast<float>().transpose();
  rotation.row(2) = (-camera.direction()).cast<float>().transpose();
  const Eigen::Matrix4f vp = gpu::relative_to(view_projection, ev.origin());
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(surface_);
  glUniformMatrix4fv(glGetUniformLocation(surface_, "view_projection"), 1, GL_FALSE, vp.data());
  glUniformMatrix3fv(glGetUniformLocation(surface_, "view_rotation"), 1, GL_FALSE, rotation.data());
  uniform3(surface_, "color", color);
  mesh_.draw(ev, {.offset = 0.5f});  // in front of the renderer's surface (offset 1)
  glUseProgram(0);
}

}  // namespace mbi::viewer
