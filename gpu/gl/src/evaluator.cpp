#include <mbi/base/timer.hpp>
#include <mbi/gpu/evaluator.hpp>
#include <mbi/gpu/program.hpp>

#include "gl_util.hpp"
#include "shaders.hpp"

#include <algorithm>
#include <chrono>

namespace mbi::gpu {
namespace {

// A static vertex buffer of floats (p x comps), attribute `loc`.
GLuint float_attribute(GLuint loc, const std::vector<float>& data, int comps) {
  GLuint b = 0;
  glGenBuffers(1, &b);
  glBindBuffer(GL_ARRAY_BUFFER, b);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)),
               data.empty() ? nullptr : data.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(loc);
  glVertexAttribPointer(loc, comps, GL_FLOAT, GL_FALSE, 0, nullptr);
  return b;
}

}  // namespace

GpuEvaluator::GpuEvaluator(Context& context, const GpuOptions& options)
    : context_(context), options_(options) {
  if (options.chunk_points < 1) throw Error("GpuEvaluator: chunk_points must be >= 1");
}

GpuEvaluator::~GpuEvaluator() { release(); }

void GpuEvaluator::release() {
  const GLuint buffers[] = {element_, bary_, rest_, rest_normal_, bezier_buffer_, gradient_buffer_,
                            out_disp_, out_normal_};
  for (GLuint b : buffers)
    if (b) glDeleteBuffers(1, &b);
  const GLuint textures[] = {bezier_texture_, gradient_texture_};
  for (GLuint t : textures)
    if (t) glDeleteTextures(1, &t);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  if (program_) glDeleteProgram(program_);
  if (query_) glDeleteQueries(1, &query_);
  if (timer_) glDeleteQueries(1, &timer_);
  element_ = bary_ = rest_ = rest_normal_ = bezier_buffer_ = gradient_buffer_ = out_disp_ = out_normal_ = 0;
  bezier_texture_ = gradient_texture_ = vao_ = program_ = query_ = timer_ = 0;
}

std::string GpuEvaluator::name() const { return "gpu (" + context_.renderer() + ")"; }

void GpuEvaluator::set_points(const pipeline::PointSet& ps) {
  if (!ps.embedding) throw Error("GpuEvaluator: no embedding");
  const interp::Embedding& emb = *ps.embedding;
  const int d = emb.dim();
  const int K = (d + 1) * (d + 2) / 2;
  if (d != 2 && d != 3) throw Error("GpuEvaluator: points must be 2D or 3D");
  if (ps.rest_positions.rows() != emb.size() || ps.rest_positions.cols() != d)
    throw Error("GpuEvaluator: rest positions must be " + std::to_string(emb.size()) + " x " +
                  std::to_string(d));
  if (ps.rest_bezier.cols() != d || ps.rest_bezier.rows() % K != 0)
    throw Error("GpuEvaluator: rest Bezier points have the wrong shape");
  have_rest_normals_ = ps.rest_normals.size() > 0;
  if (have_rest_normals_ && (ps.rest_normals.rows() != emb.size() || ps.rest_normals.cols() != d))
    throw Error("GpuEvaluator: rest normals must be " + std::to_string(emb.size()) + " x " +
                  std::to_string(d));
  release();
  dim_ = d;
  points_ = emb.size();
  elements_ = ps.rest_bezier.rows() / K;
  rest_bezier_ = ps.rest_bezier;
  rest_positions_ = ps.rest_positions;
  evaluated_ = read_ = false;
  origin_.setZero();
  if (points_ > 0) {
    const Eigen::VectorXd lo = rest_positions_.colwise().minCoeff(), hi = rest_positions_.colwise().maxCoeff();
    origin_.head(d) = 0.5 * (lo + hi);
  }

  program_ = program("evaluation pass", {shaders::evaluate_vs.c_str(), nullptr}, "#define D " + std::to_string(d) + "\n",
                     {"tf_displacement", "tf_normal"});
  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  const size_t p = static_cast<size_t>(points_);
  // element ids: an integer attribute (glVertexAttribIPointer, not glVertexAttribPointer)
  {
    std::vector<GLint> ids(p);
    for (size_t i = 0; i < p; ++i) ids[i] = emb.element(static_cast<Eigen::Index>(i));
    glGenBuffers(1, &element_);
    glBindBuffer(GL_ARRAY_BUFFER, element_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(p * sizeof(GLint)), ids.empty() ? nullptr : ids.data(),
                 GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribIPointer(0, 1, GL_INT, 0, nullptr);
  }
  {
    std::vector<float> b(p * 4, 0.0f), n(p * 3, 0.0f), r(p * 3, 0.0f);
    for (size_t i = 0; i < p; ++i) {
      const auto ii = static_cast<Eigen::Index>(i);
      for (int k = 0; k <= d; ++k) b[4 * i + static_cast<size_t>(k)] = static_cast<float>(emb.bary(ii, k));
      for (int c = 0; c < d; ++c) {
        r[3 * i + static_cast<size_t>(c)] = static_cast<float>(rest_positions_(ii, c) - origin_(c));
        if (have_rest_normals_) n[3 * i + static_cast<size_t>(c)] = static_cast<float>(ps.rest_normals(ii, c));
      }
    }
    bary_ = float_attribute(1, b, 4);
    rest_normal_ = float_attribute(2, n, 3);
    glGenBuffers(1, &rest_);  // not read by the pass: the renderer's rest positions
    glBindBuffer(GL_ARRAY_BUFFER, rest_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(r.size() * sizeof(float)), r.empty() ? nullptr : r.data(),
                 GL_STATIC_DRAW);
  }
  // basis gradients (for normals), vec4 per (element, corner)
  {
    std::vector<float> g(static_cast<size_t>(elements_) * static_cast<size_t>(d + 1) * 4, 0.0f);
    if (emb.gradients.rows() == elements_ * (d + 1))
      for (Eigen::Index q = 0; q < emb.gradients.rows(); ++q)
        for (int c = 0; c < d; ++c) g[4 * static_cast<size_t>(q) + static_cast<size_t>(c)] = static_cast<float>(emb.gradients(q, c));
    glGenBuffers(1, &gradient_buffer_);
    glBindBuffer(GL_TEXTURE_BUFFER, gradient_buffer_);
    glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(std::max<size_t>(g.size(), 4) * sizeof(float)),
                 g.empty() ? nullptr : g.data(), GL_STATIC_DRAW);
    glGenTextures(1, &gradient_texture_);
    glBindTexture(GL_TEXTURE_BUFFER, gradient_texture_);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, gradient_buffer_);
  }
  glGenBuffers(1, &bezier_buffer_);
  glGenTextures(1, &bezier_texture_);
  // outputs: displacement and normal, vec3 float per point
  for (GLuint* b : {&out_disp_, &out_normal_}) {
    glGenBuffers(1, b);
    glBindBuffer(GL_ARRAY_BUFFER, *b);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(std::max<size_t>(p, 1) * 3 * sizeof(float)), nullptr,
                 GL_DYNAMIC_COPY);
  }
  glGenQueries(1, &query_);
  glGenQueries(1, &timer_);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  detail::check("GpuEvaluator::set_points");
}

void GpuEvaluator::evaluate(const interp::BezierPoints& B, bool normals) {
  if (!program_) throw Error("GpuEvaluator: evaluate() before set_points()");
  if (B.rows() != rest_bezier_.rows() || B.cols() != rest_bezier_.cols())
    throw Error("GpuEvaluator: Bezier points must be " + std::to_string(rest_bezier_.rows()) + " x " +
                  std::to_string(rest_bezier_.cols()));
  if (normals && !have_rest_normals_)
    throw Error("GpuEvaluator: normals asked for, but no rest normals were given");
  // upload: the displacement control points as vec4 floats, into an orphaned buffer (a fresh
  // store, so the driver never waits for the last pass or copies to avoid stalling)
  auto t0 = Clock::now();
  const Eigen::Index rows = B.rows();
  upload_.assign(static_cast<size_t>(std::max<Eigen::Index>(rows, 1)) * 4, 0.0f);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (int c = 0; c < dim_; ++c)
      upload_[4 * static_cast<size_t>(r) + static_cast<size_t>(c)] = static_cast<float>(B(r, c) - rest_bezier_(r, c));
  const auto bytes = static_cast<GLsizeiptr>(upload_.size() * sizeof(float));
  glBindBuffer(GL_TEXTURE_BUFFER, bezier_buffer_);
  glBufferData(GL_TEXTURE_BUFFER, bytes, nullptr, GL_STREAM_DRAW);
  glBufferSubData(GL_TEXTURE_BUFFER, 0, bytes, upload_.data());
  glBindTexture(GL_TEXTURE_BUFFER, bezier_texture_);
  glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, bezier_buffer_);
  if (options_.measure) glFinish();
  timings_.upload_ms = ms_since(t0);

  // the pass: rasterizer off, a complete framebuffer bound (a surfaceless context has none)
  t0 = Clock::now();
  const bool timer = options_.measure && !context_.software();
  if (timer) glBeginQuery(GL_TIME_ELAPSED, timer_);
  glBindFramebuffer(GL_FRAMEBUFFER, context_.dummy_framebuffer());
  glUseProgram(program_);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_BUFFER, bezier_texture_);
  glUniform1i(glGetUniformLocation(program_, "bezier"), 0);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_BUFFER, gradient_texture_);
  glUniform1i(glGetUniformLocation(program_, "gradients"), 1);
  glUniform1i(glGetUniformLocation(program_, "with_normals"), normals ? 1 : 0);
  glBindVertexArray(vao_);
  glEnable(GL_RASTERIZER_DISCARD);
  primitives_ = 0;
  draws_ = 0;
  for (long long first = 0; first < points_; first += options_.chunk_points) {
    const long long count = std::min(options_.chunk_points, points_ - first);
    const auto offset = static_cast<GLintptr>(first * 3 * static_cast<long long>(sizeof(float)));
    const auto size = static_cast<GLsizeiptr>(count * 3 * static_cast<long long>(sizeof(float)));
    glBindBufferRange(GL_TRANSFORM_FEEDBACK_BUFFER, 0, out_disp_, offset, size);
    glBindBufferRange(GL_TRANSFORM_FEEDBACK_BUFFER, 1, out_normal_, offset, size);
    glBeginQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, query_);
    glBeginTransformFeedback(GL_POINTS);
    glDrawArrays(GL_POINTS, static_cast<GLint>(first), static_cast<GLsizei>(count));
    glEndTransformFeedback();
    glEndQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN);
    GLuint written = 0;
    glGetQueryObjectuiv(query_, GL_QUERY_RESULT, &written);
    primitives_ += written;
    ++draws_;
  }
  glDisable(GL_RASTERIZER_DISCARD);
  glBindVertexArray(0);
  glUseProgram(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (timer) glEndQuery(GL_TIME_ELAPSED);
  if (options_.measure) {
    glFinish();
    timings_.pass_ms = ms_since(t0);
    if (timer) {
      GLuint64 ns = 0;
      glGetQueryObjectui64v(timer_, GL_QUERY_RESULT, &ns);
      timings_.pass_ms = static_cast<double>(ns) * 1e-6;
    }
  } else {
    timings_.pass_ms = 0;
  }
  detail::check("GpuEvaluator::evaluate");
  if (primitives_ != points_)
    throw Error("GpuEvaluator: the pass captured " + std::to_string(primitives_) + " of " +
                  std::to_string(points_) + " points (" + context_.renderer() + ")");
  have_normals_ = normals;
  evaluated_ = true;
  read_ = false;
}

void GpuEvaluator::set_results(const Eigen::MatrixXd& positions, const Eigen::MatrixXd& normals) {
  if (positions.rows() != points_ || positions.cols() != dim_ ||
      (normals.size() > 0 && (normals.rows() != points_ || normals.cols() != dim_)))
    throw Error("GpuEvaluator: results must be " + std::to_string(points_) + " x " + std::to_string(dim_));
  const size_t p = static_cast<size_t>(points_);
  std::vector<float>& buf = upload_;  // staging kept between frames (evaluate() refills it too)
  buf.assign(p * 3, 0.0f);
  auto upload = [&](unsigned buffer) {
    glBindBuffer(GL_ARRAY_BUFFER, buffer);
    glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(buf.size() * sizeof(float)), buf.data());
  };
  for (size_t i = 0; i < p; ++i)
    for (int c = 0; c < dim_; ++c) {
      const auto ii = static_cast<Eigen::Index>(i);
      buf[3 * i + static_cast<size_t>(c)] = static_cast<float>(positions(ii, c) - rest_positions_(ii, c));
    }
  if (p > 0) upload(out_disp_);
  have_normals_ = normals.size() > 0;
  if (have_normals_ && p > 0) {
    for (size_t i = 0; i < p; ++i)
      for (int c = 0; c < dim_; ++c)
        buf[3 * i + static_cast<size_t>(c)] = static_cast<float>(normals(static_cast<Eigen::Index>(i), c));
    upload(out_normal_);
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  detail::check("GpuEvaluator::set_results");
  positions_ = positions;
  normals_ = normals;
  evaluated_ = read_ = true;
}

const Eigen::MatrixXd& GpuEvaluator::positions() {
  if (!evaluated_) throw Error("GpuEvaluator: positions() before evaluate()");
  if (!read_) {
    const size_t p = static_cast<size_t>(points_);
    std::vector<float> buf(p * 3);
    const auto bytes = static_cast<GLsizeiptr>(buf.size() * sizeof(float));
    positions_ = rest_positions_;
    if (p > 0) {
      glBindBuffer(GL_ARRAY_BUFFER, out_disp_);
      glGetBufferSubData(GL_ARRAY_BUFFER, 0, bytes, buf.data());
      for (size_t i = 0; i < p; ++i)
        for (int c = 0; c < dim_; ++c)
          positions_(static_cast<Eigen::Index>(i), c) += static_cast<double>(buf[3 * i + static_cast<size_t>(c)]);
    }
    normals_.resize(have_normals_ ? static_cast<Eigen::Index>(p) : 0, dim_);
    if (have_normals_ && p > 0) {
      glBindBuffer(GL_ARRAY_BUFFER, out_normal_);
      glGetBufferSubData(GL_ARRAY_BUFFER, 0, bytes, buf.data());
      for (size_t i = 0; i < p; ++i)
        for (int c = 0; c < dim_; ++c)
          normals_(static_cast<Eigen::Index>(i), c) = static_cast<double>(buf[3 * i + static_cast<size_t>(c)]);
    }
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    detail::check("GpuEvaluator: read back");
    read_ = true;
  }
  return positions_;
}

const Eigen::MatrixXd& GpuEvaluator::normals() {
  positions();
  return normals_;
}

}  // namespace mbi::gpu
