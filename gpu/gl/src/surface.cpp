#include <mbi/gpu/surface.hpp>

#include "gl_util.hpp"

#include <string>
#include <vector>

namespace mbi::gpu {
namespace {

void attribute(GLuint location, GLuint buffer) {
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glEnableVertexAttribArray(location);
  glVertexAttribPointer(location, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
}

}  // namespace

Eigen::Matrix4f relative_to(const Eigen::Matrix4d& view_projection, const Eigen::Vector3d& origin) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.block<3, 1>(0, 3) = origin;
  return (view_projection * T).cast<float>();
}

Surface::Surface() {
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &index_);
  glGenBuffers(1, &colors_);
  detail::check("Surface");
}

Surface::~Surface() {
  const GLuint buffers[] = {index_, colors_};
  glDeleteBuffers(2, buffers);
  glDeleteVertexArrays(1, &vao_);
}

void Surface::set_faces(const Eigen::Ref<const Eigen::MatrixXi>& F) {
  if (F.cols() != 3 && F.rows() > 0)
    throw Error("Surface: faces must be t x 3, not t x " + std::to_string(F.cols()));
  std::vector<GLuint> idx(static_cast<size_t>(F.rows()) * 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      if (F(f, k) < 0) throw Error("Surface: negative index in face " + std::to_string(f));
      idx[3 * static_cast<size_t>(f) + static_cast<size_t>(k)] = static_cast<GLuint>(F(f, k));
    }
  glBindVertexArray(vao_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(idx.size() * sizeof(GLuint)),
               idx.empty() ? nullptr : idx.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  indices_ = static_cast<long long>(idx.size());
  detail::check("Surface::set_faces");
}

void Surface::draw(const GpuEvaluator& ev, const SurfaceInputs& in) {
  if (in.normals && !ev.has_normals()) throw Error("Surface: normals asked of a pass without them");
  if (!in.colors.empty() && in.colors.size() != 3 * static_cast<size_t>(ev.points()))
    throw Error("Surface: " + std::to_string(in.colors.size()) + " colour values for " +
                std::to_string(ev.points()) + " points (3 a point)");
  glBindVertexArray(vao_);
  attribute(0, ev.rest_buffer());
  attribute(1, ev.displacement_buffer());
  if (in.normals) attribute(2, ev.normal_buffer());
  else glDisableVertexAttribArray(2);
  if (!in.colors.empty()) {
    glBindBuffer(GL_ARRAY_BUFFER, colors_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(in.colors.size_bytes()), in.colors.data(),
                 GL_STREAM_DRAW);
    attribute(3, colors_);
  } else {
    glDisableVertexAttribArray(3);
  }
  if (in.offset > 0) {
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(in.offset, in.offset);
  }
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(indices_), GL_UNSIGNED_INT, nullptr);
  if (in.offset > 0) glDisable(GL_POLYGON_OFFSET_FILL);
  glBindVertexArray(0);
}

}  // namespace mbi::gpu
