#include "crease_layer.hpp"

#include "gl_program.hpp"

#include <epoxy/gl.h>

#include <algorithm>
#include <string>

namespace mbi::viewer {
namespace {

// gpu::Renderer's mesh shaders with a colour per vertex.
const char* kVertex = R"(
layout(location = 0) in vec3 rest;
layout(location = 1) in vec3 displacement;
layout(location = 2) in vec3 normal;
layout(location = 3) in vec3 color;
uniform mat4 view_projection;
out vec3 v_normal;
out vec3 v_color;
void main() {
  v_normal = normal;
  v_color = color;
  gl_Position = view_projection * vec4(rest + displacement, 1.0);
}
)";
const char* kFragment = R"(
in vec3 v_normal;
in vec3 v_color;
uniform vec3 eye_direction;
out vec4 frag;
void main() {
  float lambert = abs(dot(normalize(v_normal), -eye_direction));
  frag = vec4(v_color * (0.25 + 0.75 * lambert), 1.0);
}
)";

}  // namespace

CreaseLayer::CreaseLayer(const Stage& stage)
    : creases_(stage.U, stage.T),
      near_(creases_.near_faces(stage.pipe.embedding())),
      program_(link_program("crease colours", kVertex, kFragment)) {
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &index_);
  glGenBuffers(1, &colors_);
  std::vector<GLuint> idx(static_cast<size_t>(stage.F.size()));
  for (Eigen::Index f = 0; f < stage.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) idx[static_cast<size_t>(3 * f + k)] = static_cast<GLuint>(stage.F(f, k));
  glBindVertexArray(vao_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(idx.size() * sizeof(GLuint)), idx.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  indices_ = static_cast<long long>(idx.size());
}

CreaseLayer::~CreaseLayer() {
  glDeleteBuffers(1, &index_);
  glDeleteBuffers(1, &colors_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void CreaseLayer::update(Stage& stage) {
  std::vector<Eigen::VectorXd> jumps;
  top_ = 0;
  for (pipeline::Method m : stage.views) {
    jumps.push_back(creases_.face_jumps(stage.pipe, m));
    if (jumps.back().size()) top_ = std::max(top_, jumps.back().maxCoeff());
  }
  const double top = pipeline::crease_scale(top_);
  views_.resize(jumps.size());
  for (size_t k = 0; k < jumps.size(); ++k) {
    const Eigen::VectorXd v = creases_.point_values(stage.pipe.embedding(), jumps[k]);
    CreaseView& cv = views_[k];
    cv.rgb.resize(static_cast<size_t>(v.size()) * 3);
    cv.mean_jump = jumps[k].size() ? jumps[k].mean() : 0.0;
    double near_sum = 0;
    long near_count = 0;
    for (Eigen::Index q = 0; q < v.size(); ++q) {
      const Eigen::Vector3d c = pipeline::crease_color(v(q) / top);
      for (int i = 0; i < 3; ++i) cv.rgb[static_cast<size_t>(3 * q + i)] = static_cast<float>(c(i));
      if (near_[static_cast<size_t>(q)]) near_sum += std::min(v(q) / top, 1.0), ++near_count;
    }
    cv.mean_near = near_count ? near_sum / static_cast<double>(near_count) : 0.0;
  }
}

void CreaseLayer::draw(const gpu::GpuEvaluator& ev, size_t k, const Eigen::Matrix4d& view_projection,
                       const Eigen::Vector3d& eye_direction) {
  if (k >= views_.size()) return;
  const std::vector<float>& rgb = views_[k].rgb;
  Eigen::Matrix4d shift = Eigen::Matrix4d::Identity();  // GPU positions are relative to the origin
  shift.block<3, 1>(0, 3) = ev.origin();
  const Eigen::Matrix4f vp = (view_projection * shift).cast<float>();
  const Eigen::Vector3f eye = eye_direction.normalized().cast<float>();
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glUseProgram(program_);
  glUniformMatrix4fv(glGetUniformLocation(program_, "view_projection"), 1, GL_FALSE, vp.data());
  glUniform3f(glGetUniformLocation(program_, "eye_direction"), eye.x(), eye.y(), eye.z());
  glBindVertexArray(vao_);
  const GLuint sources[3] = {ev.rest_buffer(), ev.displacement_buffer(), ev.normal_buffer()};
  for (GLuint loc = 0; loc < 3; ++loc) {
    glBindBuffer(GL_ARRAY_BUFFER, sources[loc]);
    glEnableVertexAttribArray(loc);
    glVertexAttribPointer(loc, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  }
  glBindBuffer(GL_ARRAY_BUFFER, colors_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(rgb.size() * sizeof(float)), rgb.data(), GL_STREAM_DRAW);
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(0.5f, 0.5f);  // in front of the renderer's surface (offset 1), behind its wireframe
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(indices_), GL_UNSIGNED_INT, nullptr);
  glDisable(GL_POLYGON_OFFSET_FILL);
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
}

}  // namespace mbi::viewer
