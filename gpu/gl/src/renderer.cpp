#include <mbi/gpu/renderer.hpp>

#include <mbi/gpu/program.hpp>

#include "gl_util.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <set>
#include <string>
#include <utility>

namespace mbi::gpu {
namespace {

// The rasteriser's orthographic framing (raster.cpp, Projector) as a matrix acting on world
// positions: clip x, y from the screen mapping, z from the depth range of the bounds.
Eigen::Matrix4d ortho_view(const raster::View& v, int w, int h) {
  const Eigen::Vector3d fwd = v.direction.normalized();
  const Eigen::Vector3d right = fwd.cross(v.up).normalized();
  const Eigen::Vector3d up = right.cross(fwd);
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, z0 = 1e300, z1 = -1e300;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p((c & 1) ? v.bounds_max.x() : v.bounds_min.x(),
                            (c & 2) ? v.bounds_max.y() : v.bounds_min.y(),
                            (c & 4) ? v.bounds_max.z() : v.bounds_min.z());
    x0 = std::min(x0, p.dot(right)), x1 = std::max(x1, p.dot(right));
    y0 = std::min(y0, p.dot(up)), y1 = std::max(y1, p.dot(up));
    z0 = std::min(z0, p.dot(fwd)), z1 = std::max(z1, p.dot(fwd));
  }
  const double sx = (x1 - x0) * (1 + 2 * v.margin), sy = (y1 - y0) * (1 + 2 * v.margin);
  const double scale = std::min(w / std::max(sx, 1e-300), h / std::max(sy, 1e-300));
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  const double pad = 0.5 * std::max(z1 - z0, 1e-12);  // geometry slightly outside the bounds
  z0 -= pad, z1 += pad;
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  M.block<1, 3>(0, 0) = (2 * scale / w) * right.transpose();
  M(0, 3) = -2 * scale / w * cx;
  M.block<1, 3>(1, 0) = (2 * scale / h) * up.transpose();
  M(1, 3) = -2 * scale / h * cy;
  M.block<1, 3>(2, 0) = (2 / (z1 - z0)) * fwd.transpose();
  M(2, 3) = -2 * z0 / (z1 - z0) - 1;
  M(3, 3) = 1;
  return M;
}

// Depth test on and a program of gpu::shaders::mesh in use with its camera uniforms; returns its
// view_projection (relative to the evaluator's origin).
Eigen::Matrix4f use_mesh_program(GLuint program, const GpuEvaluator& ev, const Eigen::Matrix4d& view_projection,
                                 const Eigen::Vector3d& eye_direction) {
  if (ev.dim() != 3 || !ev.has_normals())
    throw Error("Renderer: needs a 3D evaluation with normals");
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  const Eigen::Matrix4f vp = relative_to(view_projection, ev.origin());
  const Eigen::Vector3f eye = eye_direction.normalized().cast<float>();
  glUseProgram(program);
  glUniformMatrix4fv(glGetUniformLocation(program, "view_projection"), 1, GL_FALSE, vp.data());
  glUniform3f(glGetUniformLocation(program, "eye_direction"), eye.x(), eye.y(), eye.z());
  return vp;
}

}  // namespace

Renderer::Renderer(Context& context) : context_(context) {
  mesh_program_ = program("renderer surface", shaders::mesh);
  line_program_ = program("renderer lines", shaders::line);
  texture_program_ = program("renderer picture", shaders::texture);
  glGenVertexArrays(1, &line_vao_);
  glGenBuffers(1, &line_buffer_);
  detail::check("Renderer");
}

Renderer::~Renderer() {
  if (line_buffer_) glDeleteBuffers(1, &line_buffer_);
  if (line_vao_) glDeleteVertexArrays(1, &line_vao_);
  if (mesh_buffers_[0]) glDeleteBuffers(3, mesh_buffers_);
  if (mesh_vao_) glDeleteVertexArrays(1, &mesh_vao_);
  if (fbo_) glDeleteFramebuffers(1, &fbo_);
  const GLuint rbs[] = {color_, depth_};
  for (GLuint r : rbs)
    if (r) glDeleteRenderbuffers(1, &r);
  if (mesh_program_) glDeleteProgram(mesh_program_);
  if (colors_program_) glDeleteProgram(colors_program_);
  if (line_program_) glDeleteProgram(line_program_);
  if (texture_program_) glDeleteProgram(texture_program_);
  if (texture_) glDeleteTextures(1, &texture_);
  if (material_program_) glDeleteProgram(material_program_);
  if (ground_program_) glDeleteProgram(ground_program_);
  if (ground_corners_) glDeleteBuffers(1, &ground_corners_);
  if (ground_vao_) glDeleteVertexArrays(1, &ground_vao_);
}

void Renderer::set_faces(const Eigen::Ref<const Eigen::MatrixXi>& F) { surface_.set_faces(F); }

void Renderer::ensure_target(int width, int height) {
  if (width == width_ && height == height_ && fbo_) return;
  if (!fbo_) {
    glGenFramebuffers(1, &fbo_);
    glGenRenderbuffers(1, &color_);
    glGenRenderbuffers(1, &depth_);
  }
  glBindRenderbuffer(GL_RENDERBUFFER, color_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw Error("Renderer: incomplete framebuffer of " + std::to_string(width) + " x " + std::to_string(height));
  width_ = width;
  height_ = height;
}

Eigen::Matrix4d Renderer::view_matrix(const raster::View& view, int width, int height) {
  return ortho_view(view, width, height);
}

void Renderer::draw(const GpuEvaluator& ev, const Eigen::Matrix4d& view_projection,
                    const Eigen::Vector3d& eye_direction, const Eigen::Vector3d& color,
                    const Eigen::MatrixXd* wire_X, const Eigen::MatrixXi* wire_T) {
  const Eigen::Matrix4f vp = use_mesh_program(mesh_program_, ev, view_projection, eye_direction);
  glUniform3f(glGetUniformLocation(mesh_program_, "color"), static_cast<float>(color.x()),
              static_cast<float>(color.y()), static_cast<float>(color.z()));
  surface_.draw(ev, {.offset = 1.0f});  // behind the wireframe
  if (wire_X && wire_T && wire_T->cols() == 4) {
    if (wire_T->rows() != edges_of_ || wire_T->size() == 0 || edges_.empty()) {  // once per control mesh
      std::set<std::pair<int, int>> unique;
      for (Eigen::Index e = 0; e < wire_T->rows(); ++e)
        for (int a = 0; a < 4; ++a)
          for (int b = a + 1; b < 4; ++b) unique.insert(std::minmax((*wire_T)(e, a), (*wire_T)(e, b)));
      edges_.assign(unique.begin(), unique.end());
      edges_of_ = wire_T->rows();
    }
    std::vector<float> lines;
    lines.reserve(edges_.size() * 6);
    for (const auto& [a, b] : edges_)
      for (int v : {a, b})
        for (int c = 0; c < 3; ++c) lines.push_back(static_cast<float>((*wire_X)(v, c) - ev.origin()(c)));
    glUseProgram(line_program_);
    glUniformMatrix4fv(glGetUniformLocation(line_program_, "view_projection"), 1, GL_FALSE, vp.data());
    glUniform3f(glGetUniformLocation(line_program_, "color"), 0.16f, 0.16f, 0.16f);
    glBindVertexArray(line_vao_);
    glBindBuffer(GL_ARRAY_BUFFER, line_buffer_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(lines.size() * sizeof(float)), lines.data(), GL_STREAM_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(lines.size() / 3));
  }
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
  detail::check("Renderer::draw");
}

void Renderer::draw_colors(const GpuEvaluator& ev, const Eigen::Matrix4d& view_projection,
                           const Eigen::Vector3d& eye_direction, std::span<const float> rgb) {
  if (!colors_program_) colors_program_ = program("renderer colours", shaders::mesh, "#define VERTEX_COLOR\n");
  use_mesh_program(colors_program_, ev, view_projection, eye_direction);
  surface_.draw(ev, {.colors = rgb, .offset = 0.5f});  // in front of draw()'s (offset 1), behind its wireframe
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
  detail::check("Renderer::draw_colors");
}

void Renderer::draw_textured(const GpuEvaluator& ev, const Eigen::Matrix4d& view_projection,
                             const io::Image& image) {
  if (ev.dim() != 2) throw Error("Renderer: textured drawing is for 2D evaluations");
  if (!texture_ || texture_image_ != &image) {
    if (!texture_) glGenTextures(1, &texture_);
    glBindTexture(GL_TEXTURE_2D, texture_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, image.width, image.height, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 image.rgb.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    texture_image_ = &image;
  }
  const Eigen::Matrix4f vp = relative_to(view_projection, ev.origin());
  glUseProgram(texture_program_);
  glUniformMatrix4fv(glGetUniformLocation(texture_program_, "view_projection"), 1, GL_FALSE, vp.data());
  glUniform3f(glGetUniformLocation(texture_program_, "origin"), static_cast<float>(ev.origin().x()),
              static_cast<float>(ev.origin().y()), static_cast<float>(ev.origin().z()));
  glUniform2f(glGetUniformLocation(texture_program_, "image_size"), static_cast<float>(image.width),
              static_cast<float>(image.height));
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glUniform1i(glGetUniformLocation(texture_program_, "image"), 0);
  surface_.draw(ev, {.normals = false});
  glUseProgram(0);
  detail::check("Renderer::draw_textured");
}

void Renderer::draw_mesh(const Eigen::MatrixXd& V, const Eigen::MatrixXd& N, const Eigen::MatrixXi& F,
                         const Eigen::Matrix4d& view_projection, const Eigen::Vector3d& eye_direction,
                         const Eigen::Vector3d& color) {
  if (V.cols() != 3 || N.rows() != V.rows() || N.cols() != 3 || F.cols() != 3)
    throw Error("Renderer::draw_mesh: V and N need n x 3, F t x 3");
  if (F.size() > 0 && (F.minCoeff() < 0 || F.maxCoeff() >= V.rows()))
    throw Error("Renderer::draw_mesh: F indexes vertices outside V's " + std::to_string(V.rows()) + " rows");
  if (F.rows() == 0) return;
  if (!mesh_vao_) {
    glGenVertexArrays(1, &mesh_vao_);
    glGenBuffers(3, mesh_buffers_);
  }
  const Eigen::Vector3d origin = V.colwise().mean().transpose();
  const Eigen::MatrixXf P = (V.rowwise() - origin.transpose()).cast<float>().transpose();  // 3 x n: rows of floats
  const Eigen::MatrixXf Nf = N.cast<float>().transpose();
  const Eigen::Matrix<unsigned, Eigen::Dynamic, Eigen::Dynamic> I = F.cast<unsigned>().transpose();
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  const Eigen::Matrix4f vp = relative_to(view_projection, origin);
  const Eigen::Vector3f eye = eye_direction.normalized().cast<float>();
  glUseProgram(mesh_program_);
  glUniformMatrix4fv(glGetUniformLocation(mesh_program_, "view_projection"), 1, GL_FALSE, vp.data());
  glUniform3f(glGetUniformLocation(mesh_program_, "eye_direction"), eye.x(), eye.y(), eye.z());
  glUniform3f(glGetUniformLocation(mesh_program_, "color"), static_cast<float>(color.x()),
              static_cast<float>(color.y()), static_cast<float>(color.z()));
  glBindVertexArray(mesh_vao_);
  const float* arrays[2] = {P.data(), Nf.data()};
  for (int k = 0; k < 2; ++k) {  // locations 0 (rest) and 2 (normal); the displacement stays 0
    glBindBuffer(GL_ARRAY_BUFFER, mesh_buffers_[k]);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(V.size() * sizeof(float)), arrays[k], GL_STREAM_DRAW);
    glEnableVertexAttribArray(static_cast<GLuint>(2 * k));
    glVertexAttribPointer(static_cast<GLuint>(2 * k), 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  }
  glDisableVertexAttribArray(1);
  glVertexAttrib3f(1, 0.0f, 0.0f, 0.0f);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, mesh_buffers_[2]);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(F.size() * sizeof(unsigned)), I.data(), GL_STREAM_DRAW);
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(F.size()), GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
  detail::check("Renderer::draw_mesh");
}

void Renderer::draw_points(const Eigen::MatrixXd& points, const Eigen::Matrix4d& view_projection,
                           const Eigen::Vector3d& color, float size) {
  if (points.rows() == 0) return;
  const Eigen::Vector3d origin = points.colwise().mean().transpose();
  std::vector<float> data;
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    for (int c = 0; c < 3; ++c) data.push_back(static_cast<float>(points(i, c) - origin(c)));
  const Eigen::Matrix4f vp = relative_to(view_projection, origin);
  glUseProgram(line_program_);
  glUniformMatrix4fv(glGetUniformLocation(line_program_, "view_projection"), 1, GL_FALSE, vp.data());
  glUniform3f(glGetUniformLocation(line_program_, "color"), static_cast<float>(color.x()),
              static_cast<float>(color.y()), static_cast<float>(color.z()));
  glBindVertexArray(line_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, line_buffer_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(), GL_STREAM_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glPointSize(size);
  glDrawArrays(GL_POINTS, 0, static_cast<GLsizei>(points.rows()));
  glBindVertexArray(0);
  glUseProgram(0);
  detail::check("Renderer::draw_points");
}

io::Image Renderer::render(const GpuEvaluator& ev, const raster::View& view, int width, int height,
                           const Eigen::Vector3d& color, const Eigen::MatrixXd* wire_X,
                           const Eigen::MatrixXi* wire_T, const std::vector<raster::Solid>& solids) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw Error("Renderer: picture size " + std::to_string(width) + " x " + std::to_string(height) +
                  " out of range [1, 16384]");
  ensure_target(width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width, height);
  glClearColor(1, 1, 1, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  const Eigen::Matrix4d vp = ortho_view(view, width, height);
  draw(ev, vp, view.direction, color, wire_X, wire_T);
  for (const raster::Solid& s : solids) {  // unlit: normals toward the eye give the colour itself
    const Eigen::MatrixXd N = s.shaded ? raster::vertex_normals(s.V, s.F)
                                       : Eigen::MatrixXd(view.direction.normalized().transpose().replicate(s.V.rows(), 1));
    draw_mesh(s.V, N, s.F, vp, view.direction, s.color);
  }
  io::Image img = read_picture(width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  detail::check("Renderer::render");
  return img;
}

io::Image read_picture(int width, int height) {
  if (width < 0 || height < 0)
    throw Error("read_picture: negative size " + std::to_string(width) + " x " + std::to_string(height));
  std::vector<std::uint8_t> rgba(static_cast<size_t>(width) * height * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  io::Image img(width, height);
  for (int y = 0; y < height; ++y)  // GL rows start at the bottom
    for (int x = 0; x < width; ++x) {
      const std::uint8_t* s = rgba.data() + (static_cast<size_t>(height - 1 - y) * width + x) * 4;
      std::uint8_t* d = img.at(x, y);
      d[0] = s[0], d[1] = s[1], d[2] = s[2];
    }
  return img;
}

}  // namespace mbi::gpu
