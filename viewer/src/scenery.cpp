#include "scenery.hpp"

#include "gl_program.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

namespace mbi::viewer {
namespace {

const char* kSurfaceVertex = R"(
layout(location = 0) in vec3 rest;
layout(location = 1) in vec3 displacement;
layout(location = 2) in vec3 normal;
uniform mat4 view_projection;
uniform mat3 view_rotation;
out vec3 v_normal;
void main() {
  v_normal = view_rotation * normal;
  gl_Position = view_projection * vec4(rest + displacement, 1.0);
}
)";

// A clay matcap: a key light from the upper left, a sky-to-ground fill, a soft rim and a small
// highlight, all from the normal in camera space (x right, y up, z toward the eye). Two-sided:
// models with inward or mixed normals look the same.
const char* kSurfaceFragment = R"(
in vec3 v_normal;
uniform vec3 color;
out vec4 frag;
void main() {
  vec3 n = normalize(v_normal);
  if (n.z < 0.0) n = -n;
  vec3 key = normalize(vec3(-0.45, 0.6, 0.65));
  float diffuse = max(dot(n, key), 0.0);
  vec3 fill = mix(vec3(0.32, 0.3, 0.28), vec3(0.55, 0.6, 0.68), 0.5 + 0.5 * n.y);
  // powers by multiplication: pow() is costly on a software renderer
  float r = 1.0 - n.z, rim = r * r * r;
  float h = max(dot(reflect(-key, n), vec3(0.0, 0.0, 1.0)), 0.0), h2 = h * h, h4 = h2 * h2, h8 = h4 * h4;
  vec3 c = color * (fill + 0.75 * diffuse) + 0.18 * (h8 * h8 * h8) + 0.12 * rim;
  frag = vec4(clamp(c, 0.0, 1.0), 1.0);
}
)";

const char* kGroundVertex = R"(
layout(location = 0) in vec2 corner;
uniform mat4 view_projection;
uniform vec3 center, e1, e2;
uniform float half_side;
out vec2 p;
void main() {
  p = corner * half_side;
  gl_Position = view_projection * vec4(center + p.x * e1 + p.y * e2, 1.0);
}
)";

// Grid lines one pixel wide whatever the distance (fwidth), every tenth darker; the shadow a
// rounded rectangle whose edge fades over `soft`; the square's edge fades into the background.
const char* kGroundFragment = R"(
in vec2 p;
uniform float half_side, spacing, soft;
uniform vec2 shadow_center, shadow_half;
uniform vec3 background;
out vec4 frag;
float lines(vec2 q) {
  vec2 g = abs(fract(q - 0.5) - 0.5) / max(fwidth(q), vec2(1e-6));
  return 1.0 - min(min(g.x, g.y), 1.0);
}
void main() {
  vec2 q = p / spacing;
  float grid = max(0.5 * lines(q), lines(q / 10.0));
  float d = length(max(abs(p - shadow_center) - shadow_half, 0.0));
  float shadow = 0.42 * (1.0 - smoothstep(0.0, soft, d));
  vec3 ground = vec3(0.9, 0.9, 0.89) * (1.0 - 0.12 * grid) * (1.0 - shadow);
  float fade = smoothstep(half_side, 0.55 * half_side, length(p));
  frag = vec4(mix(background, ground, fade), 1.0);
}
)";

Eigen::Matrix4f relative(const Eigen::Matrix4d& vp, const Eigen::Vector3d& origin) {
  Eigen::Matrix4d shift = Eigen::Matrix4d::Identity();  // GPU positions are relative to the origin
  shift.block<3, 1>(0, 3) = origin;
  return (vp * shift).cast<float>();
}

void uniform3(GLuint p, const char* name, const Eigen::Vector3d& v) {
  glUniform3f(glGetUniformLocation(p, name), static_cast<float>(v.x()), static_cast<float>(v.y()),
              static_cast<float>(v.z()));
}

}  // namespace

namespace {

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
  surface_ = link_program("surface material", kSurfaceVertex, kSurfaceFragment);
  ground_ = link_program("ground", kGroundVertex, kGroundFragment);
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &index_);
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
  const GLuint buffers[] = {index_, corners_};
  glDeleteBuffers(2, buffers);
  const GLuint vaos[] = {vao_, ground_vao_};
  glDeleteVertexArrays(2, vaos);
  glDeleteProgram(surface_);
  glDeleteProgram(ground_);
}

void Scenery::set_faces(const Eigen::MatrixXi& F) {
  std::vector<GLuint> idx(static_cast<size_t>(F.size()));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) idx[3 * static_cast<size_t>(f) + static_cast<size_t>(k)] = static_cast<GLuint>(F(f, k));
  glBindVertexArray(vao_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(idx.size() * sizeof(GLuint)), idx.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  indices_ = static_cast<long long>(idx.size());
}

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
  const Eigen::Matrix4f vp = relative(view_projection, ev.origin());
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(surface_);
  glUniformMatrix4fv(glGetUniformLocation(surface_, "view_projection"), 1, GL_FALSE, vp.data());
  glUniformMatrix3fv(glGetUniformLocation(surface_, "view_rotation"), 1, GL_FALSE, rotation.data());
  uniform3(surface_, "color", color);
  glBindVertexArray(vao_);
  const GLuint sources[3] = {ev.rest_buffer(), ev.displacement_buffer(), ev.normal_buffer()};
  for (GLuint loc = 0; loc < 3; ++loc) {
    glBindBuffer(GL_ARRAY_BUFFER, sources[loc]);
    glEnableVertexAttribArray(loc);
    glVertexAttribPointer(loc, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  }
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(0.5f, 0.5f);
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(indices_), GL_UNSIGNED_INT, nullptr);
  glDisable(GL_POLYGON_OFFSET_FILL);
  glBindVertexArray(0);
  glUseProgram(0);
}

}  // namespace mbi::viewer
