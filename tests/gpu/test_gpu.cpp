// The GPU transform-feedback evaluator and renderer against the CPU evaluator (independent
// kernel, double), on Mesa llvmpipe in CI: positions and normals, BI and modified-BI, 2D and 3D,
// small meshes and 1M points, far from the origin, split into several draws; and pictures: the
// shader programs, the surface draw with and without a colour per point, the viewer's ground and
// material.
#include <catch2/catch.hpp>

#include <mbi/generate/procedural.hpp>
#include <mbi/gpu/program.hpp>
#include <mbi/gpu/renderer.hpp>
#include <mbi/gpu/surface.hpp>
#include <mbi/gpu/window.hpp>
#include <mbi/interp.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include "common/grid_meshes.hpp"
#include "common/sanitizers.hpp"

#include <epoxy/gl.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <span>

using namespace mbi;
namespace pl = mbi::pipeline;

namespace {

gpu::Context& context() {
  static std::unique_ptr<gpu::Context> c = gpu::Context::headless();  // CI has llvmpipe: no skip
  c->make_current();
  return *c;
}

Eigen::MatrixXd points_in(const Eigen::MatrixXd& U, long long p, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.01, 0.99);
  const Eigen::RowVectorXd lo = U.colwise().minCoeff(), hi = U.colwise().maxCoeff();
  Eigen::MatrixXd P(p, U.cols());
  for (long long i = 0; i < p; ++i)
    for (Eigen::Index c = 0; c < U.cols(); ++c) P(i, c) = lo(c) + uni(rng) * (hi(c) - lo(c));
  return P;
}

Eigen::MatrixXd unit_rows(Eigen::Index p, int d, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd N(p, d);
  for (Eigen::Index i = 0; i < p; ++i)
    for (int c = 0; c < d; ++c) N(i, c) = g(rng);
  N.rowwise().normalize();
  return N;
}

Eigen::MatrixXd deform(const Eigen::MatrixXd& U) {
  if (U.cols() == 3) return test::twist_bend(U, 1.3, 0.4);
  Eigen::MatrixXd X = U;
  for (Eigen::Index i = 0; i < U.rows(); ++i) {
    X(i, 0) += 0.3 * std::sin(1.7 * U(i, 1));
    X(i, 1) += 0.2 * U(i, 0) * U(i, 0);
  }
  return X;
}

struct Pair {
  pl::FramePipeline cpu, gpu;
};

// The same frame on the CPU (double) and the GPU, with normals.
Pair pipelines(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T, const Eigen::MatrixXd& P,
               const Eigen::MatrixXd& X, pl::Method method, const gpu::GpuOptions& go = {}) {
  const Eigen::MatrixXd N = unit_rows(P.rows(), static_cast<int>(U.cols()), 5);
  pl::PipelineOptions o;
  o.method = method;
  o.normals = true;
  auto drv = [&] {
    auto d = std::make_unique<pl::GivenDriver>(U);
    d->set(X);
    return d;
  };
  const interp::Embedding emb = interp::embed(U, T, P);
  return {pl::FramePipeline(U, T, emb, drv(), o, nullptr, N),
          pl::FramePipeline(U, T, emb, drv(), o, std::make_unique<gpu::GpuEvaluator>(context(), go), N)};
}

double max_abs(const Eigen::MatrixXd& A) { return A.size() ? A.cwiseAbs().maxCoeff() : 0.0; }

double extent(const Eigen::MatrixXd& P) { return (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm(); }

// The paper bar twisted and bent, evaluated on the GPU with normals (modified-BI).
struct TwistedBar {
  Eigen::MatrixXd U, X;
  Eigen::MatrixXi T, F;
  gpu::GpuEvaluator* ev = nullptr;  // owned by pipe
  std::unique_ptr<pl::FramePipeline> pipe;
};

TwistedBar twisted_bar() {
  TwistedBar b;
  Eigen::MatrixXd V;
  generate::paper_bar_control(b.U, b.T);
  generate::paper_bar_surface(V, b.F);
  b.X = generate::twist_bend(b.U, 0, 0, 0, 6, std::acos(-1.0) / 2, 0.05);
  // rest vertex normals (area weighted)
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(V.rows(), 3);
  for (Eigen::Index f = 0; f < b.F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(b.F(f, 0)), c1 = V.row(b.F(f, 1)), c2 = V.row(b.F(f, 2));
    const Eigen::RowVector3d n = (c1 - a).cross(c2 - a).transpose();
    for (int k = 0; k < 3; ++k) N.row(b.F(f, k)) += n;
  }
  N.rowwise().normalize();
  pl::PipelineOptions o;
  o.normals = true;
  auto driver = std::make_unique<pl::GivenDriver>(b.U);
  driver->set(b.X);
  auto evaluator = std::make_unique<gpu::GpuEvaluator>(context());
  b.ev = evaluator.get();
  b.pipe = std::make_unique<pl::FramePipeline>(b.U, b.T, interp::embed(b.U, b.T, V), std::move(driver), o,
                                               std::move(evaluator), N);
  REQUIRE(b.pipe->step().ok);
  return b;
}

raster::View bar_view(const TwistedBar& b) {
  return raster::frame_points(b.X, Eigen::Vector3d(-1, -0.6, -0.8), Eigen::Vector3d(0, 1, 0));
}

// A width x height colour + depth framebuffer, bound while it lives.
struct Target {
  GLuint fbo = 0, rb[2] = {};
  Target(int width, int height) {
    glGenFramebuffers(1, &fbo);
    glGenRenderbuffers(2, rb);
    glBindRenderbuffer(GL_RENDERBUFFER, rb[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glBindRenderbuffer(GL_RENDERBUFFER, rb[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    glViewport(0, 0, width, height);
  }
  ~Target() {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteRenderbuffers(2, rb);
    glDeleteFramebuffers(1, &fbo);
  }
};

// The bar drawn with gpu::shaders::mesh through a gpu::Surface: the uniform `color`, or a colour
// per point where `colors` is not empty (the program then built with VERTEX_COLOR).
io::Image draw_bar(TwistedBar& b, int w, int h, const Eigen::Vector3f& color, std::span<const float> colors) {
  const Target target(w, h);
  glClearColor(1, 1, 1, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  const GLuint p = gpu::program("test mesh", gpu::shaders::mesh, colors.empty() ? "" : "#define VERTEX_COLOR\n");
  const raster::View view = bar_view(b);
  const Eigen::Matrix4f vp = gpu::relative_to(gpu::Renderer::view_matrix(view, w, h), b.ev->origin());
  const Eigen::Vector3f eye = view.direction.normalized().cast<float>();
  glUseProgram(p);
  glUniformMatrix4fv(glGetUniformLocation(p, "view_projection"), 1, GL_FALSE, vp.data());
  glUniform3f(glGetUniformLocation(p, "eye_direction"), eye.x(), eye.y(), eye.z());
  glUniform3f(glGetUniformLocation(p, "color"), color.x(), color.y(), color.z());
  gpu::Surface surface;
  surface.set_faces(b.F);
  surface.draw(*b.ev, {.colors = colors, .offset = 1.0f});  // as the Renderer
  glUseProgram(0);
  glDeleteProgram(p);
  glDisable(GL_DEPTH_TEST);
  REQUIRE(glGetError() == GL_NO_ERROR);
  return gpu::read_picture(w, h);
}

long long covered(const io::Image& img) {
  long long n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const auto* px = img.at(x, y);
      n += !(px[0] == 255 && px[1] == 255 && px[2] == 255);
    }
  return n;
}

}  // namespace

TEST_CASE("gpu: a headless context exists (llvmpipe in CI) and reports its renderer", "[gpu]") {
  gpu::Context& c = context();
  INFO("renderer: " << c.renderer() << ", version " << c.version());
  CHECK_FALSE(c.renderer().empty());
  CHECK(c.dummy_framebuffer() != 0);
}

TEST_CASE("gpu: positions and normals equal the CPU evaluator, BI and modified-BI, 2D and 3D", "[gpu]") {
  for (int d : {2, 3}) {
    const test::Mesh m = d == 3 ? test::box_tet_mesh(5, 2, 2, Eigen::Vector3d(2.5, 1, 1))
                                : test::square_tri_mesh(6, 4, Eigen::Vector2d(3, 2));
    const Eigen::MatrixXd P = points_in(m.U, 5000, 3);
    const Eigen::MatrixXd X = deform(m.U);
    for (pl::Method method : {pl::Method::BI, pl::Method::ModifiedBI}) {
      INFO("d = " << d << ", method " << pl::method_name(method));
      Pair p = pipelines(m.U, m.T, P, X, method);
      REQUIRE(p.cpu.step().ok);
      REQUIRE(p.gpu.step().ok);
      auto& ev = dynamic_cast<gpu::GpuEvaluator&>(p.gpu.evaluator());
      CHECK(ev.primitives_written() == P.rows());  // a silent empty capture fails here
      const double size = extent(p.cpu.positions());
      CHECK(max_abs(p.gpu.positions() - p.cpu.positions()) <= 1e-5 * size);
      CHECK(max_abs(p.gpu.normals() - p.cpu.normals()) <= 1e-5);
      CHECK(p.gpu.normals().rows() == P.rows());
    }
  }
}

TEST_CASE("gpu: at rest the positions are the input (BI exactly, modified-BI to round-off)", "[gpu]") {
  const test::Mesh m = test::box_tet_mesh(3, 2, 2);
  const Eigen::MatrixXd P = points_in(m.U, 1000, 7);
  for (pl::Method method : {pl::Method::BI, pl::Method::ModifiedBI}) {
    Pair p = pipelines(m.U, m.T, P, m.U, method);
    REQUIRE(p.gpu.step().ok);
    const Eigen::MatrixXd rest = interp::embedded_positions(m.U, m.T, interp::embed(m.U, m.T, P));
    if (method == pl::Method::BI)
      CHECK(max_abs(p.gpu.positions() - rest) == 0);
    else
      CHECK(max_abs(p.gpu.positions() - rest) <= 1e-12);
  }
}

TEST_CASE("gpu: a model 1e4 units from the origin keeps its accuracy", "[gpu]") {
  test::Mesh m = test::box_tet_mesh(4, 2, 2, Eigen::Vector3d(2, 1, 1));
  const Eigen::MatrixXd P0 = points_in(m.U, 3000, 9);
  const Eigen::MatrixXd X0 = deform(m.U);
  const Eigen::RowVector3d offset(1e4, -1e4, 1e4);
  const Eigen::MatrixXd U = m.U.rowwise() + offset, P = P0.rowwise() + offset, X = X0.rowwise() + offset;
  Pair p = pipelines(U, m.T, P, X, pl::Method::ModifiedBI);
  REQUIRE(p.cpu.step().ok);
  REQUIRE(p.gpu.step().ok);
  const double size = extent(P0);
  INFO("error / size = " << max_abs(p.gpu.positions() - p.cpu.positions()) / size);
  CHECK(max_abs(p.gpu.positions() - p.cpu.positions()) <= 1e-5 * size);
  CHECK(max_abs(p.gpu.normals() - p.cpu.normals()) <= 1e-5);
}

TEST_CASE("gpu: a pass split into several draws equals the unsplit pass", "[gpu]") {
  const test::Mesh m = test::box_tet_mesh(4, 3, 2);
  const Eigen::MatrixXd P = points_in(m.U, 10007, 11);
  const Eigen::MatrixXd X = deform(m.U);
  gpu::GpuOptions split;
  split.chunk_points = 1000;
  Pair a = pipelines(m.U, m.T, P, X, pl::Method::ModifiedBI);
  Pair b = pipelines(m.U, m.T, P, X, pl::Method::ModifiedBI, split);
  REQUIRE(a.gpu.step().ok);
  REQUIRE(b.gpu.step().ok);
  CHECK(dynamic_cast<gpu::GpuEvaluator&>(a.gpu.evaluator()).draws() == 1);
  CHECK(dynamic_cast<gpu::GpuEvaluator&>(b.gpu.evaluator()).draws() == 11);
  CHECK(dynamic_cast<gpu::GpuEvaluator&>(b.gpu.evaluator()).primitives_written() == P.rows());
  CHECK(max_abs(a.gpu.positions() - b.gpu.positions()) == 0);
  CHECK(max_abs(a.gpu.normals() - b.gpu.normals()) == 0);
}

TEST_CASE("gpu: one million points equal the CPU evaluator", "[gpu][large]") {
  const test::Mesh m = test::box_tet_mesh(8, 7, 7);  // 448 control vertices
  const int n = test::sized(1000000);  // a tenth under the sanitizers
  const Eigen::MatrixXd P = points_in(m.U, n, 13);
  const Eigen::MatrixXd X = deform(m.U);
  Pair p = pipelines(m.U, m.T, P, X, pl::Method::ModifiedBI);
  REQUIRE(p.cpu.step().ok);
  REQUIRE(p.gpu.step().ok);
  auto& ev = dynamic_cast<gpu::GpuEvaluator&>(p.gpu.evaluator());
  CHECK(ev.primitives_written() == n);
  const double size = extent(p.cpu.positions());
  CHECK(max_abs(p.gpu.positions() - p.cpu.positions()) <= 1e-5 * size);
  CHECK(max_abs(p.gpu.normals() - p.cpu.normals()) <= 1e-5);
  CHECK(p.gpu.timings().evaluate_ms > 0);
}

TEST_CASE("gpu: no context when disabled, the reason is said", "[gpu]") {
  ::setenv("MBI_GL", "none", 1);
  CHECK_THROWS_WITH(gpu::Context::headless(), Catch::Contains("MBI_GL=none"));
  ::unsetenv("MBI_GL");
}

TEST_CASE("gpu: the offscreen render of the twisted bar is framed and BI differs from modified-BI", "[gpu][render]") {
  TwistedBar b = twisted_bar();
  gpu::GpuEvaluator& ev = *b.ev;
  gpu::Renderer r(context());
  r.set_faces(b.F);
  const raster::View view = bar_view(b);
  const int w = 320, h = 240;
  const io::Image mbi_img = r.render(ev, view, w, h);
  b.pipe->set_method(pl::Method::BI);
  b.pipe->evaluate();
  const io::Image bi_img = r.render(ev, view, w, h, {0.85, 0.62, 0.35}, &b.X, &b.T);
  b.pipe->set_method(pl::Method::ModifiedBI);
  for (const io::Image* img : {&mbi_img, &bi_img}) {
    long long covered = 0, border = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const auto* px = img->at(x, y);
        const bool bg = px[0] == 255 && px[1] == 255 && px[2] == 255;
        if (!bg) {
          ++covered;
          if (x == 0 || y == 0 || x == w - 1 || y == h - 1) ++border;
        }
      }
    const double frac = double(covered) / (w * h);
    INFO("covered fraction " << frac);
    CHECK(frac > 0.1);   // the object is there
    CHECK(frac < 0.9);   // and framed with a margin
    CHECK(border == 0);  // touching no border
  }
  long long differ = 0;
  for (size_t i = 0; i < mbi_img.rgb.size(); ++i) differ += mbi_img.rgb[i] != bi_img.rgb[i];
  CHECK(differ > 1000);  // BI's creases (and the wireframe) show
}

TEST_CASE("gpu: every shipped shader program links, a broken one is an error naming it with the driver's log", "[gpu]") {
  context();
  for (const gpu::ShaderSource* s : {&gpu::shaders::mesh, &gpu::shaders::texture, &gpu::shaders::line,
                                     &gpu::shaders::material, &gpu::shaders::ground}) {
    const unsigned p = gpu::program("shipped", *s);
    CHECK(p != 0);
    glDeleteProgram(p);
  }
  const unsigned colored = gpu::program("shipped", gpu::shaders::mesh, "#define VERTEX_COLOR\n");
  CHECK(glGetAttribLocation(colored, "color") == 3);
  glDeleteProgram(colored);
  const char* fragment = "out vec4 frag;\nvoid main() { frag = vec4(1.0); }\n";
  const gpu::ShaderSource no_compile{"void main() { gl_Position = undeclared; }\n", fragment};
  CHECK_THROWS_WITH(gpu::program("broken", no_compile),
                    Catch::StartsWith("OpenGL: broken: shader does not compile: ") && Catch::Contains("undeclared"));
  const gpu::ShaderSource no_link{"void f();\nvoid main() { f(); gl_Position = vec4(0.0); }\n", fragment};
  CHECK_THROWS_WITH(gpu::program("unlinked", no_link), Catch::StartsWith("OpenGL: unlinked: program does not link: "));
  CHECK_THROWS_WITH(gpu::program("empty", {}), "OpenGL: empty: no vertex shader");
  CHECK(glGetError() == GL_NO_ERROR);
}

TEST_CASE("gpu: the surface drawn with a colour per point equal to the uniform colour is the same picture, "
          "per-point colours show", "[gpu][render]") {
  TwistedBar b = twisted_bar();
  const int w = 200, h = 150;
  const Eigen::Vector3f tint(0.85f, 0.62f, 0.35f);
  const io::Image uniform = draw_bar(b, w, h, tint, {});
  std::vector<float> rgb;
  for (long long i = 0; i < b.ev->points(); ++i) rgb.insert(rgb.end(), {tint.x(), tint.y(), tint.z()});
  const io::Image per_point = draw_bar(b, w, h, {0, 0, 0}, rgb);
  CHECK(covered(uniform) > w * h / 10);
  CHECK(per_point.rgb == uniform.rgb);
  // pure red everywhere: every covered pixel red only, as many as before
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = i % 3 == 0 ? 1.0f : 0.0f;
  const io::Image red = draw_bar(b, w, h, tint, rgb);
  CHECK(covered(red) == covered(uniform));
  long long not_red = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const auto* px = red.at(x, y);
      const bool bg = px[0] == 255 && px[1] == 255 && px[2] == 255;
      not_red += !bg && (px[1] != 0 || px[2] != 0 || px[0] == 0);
    }
  CHECK(not_red == 0);
  // the renderer's picture is the same surface draw under the same shader
  gpu::Renderer r(context());
  r.set_faces(b.F);
  CHECK(r.render(*b.ev, bar_view(b), w, h, tint.cast<double>()).rgb == uniform.rgb);
}

TEST_CASE("gpu: the surface refuses faces of another shape, negative indices, colours not 3 a point and "
          "normals a pass did not make", "[gpu]") {
  TwistedBar b = twisted_bar();
  gpu::Surface surface;
  CHECK_THROWS_WITH(surface.set_faces(Eigen::MatrixXi::Zero(2, 4)), "Surface: faces must be t x 3, not t x 4");
  Eigen::MatrixXi F = b.F;
  F(3, 1) = -1;
  CHECK_THROWS_WITH(surface.set_faces(F), "Surface: negative index in face 3");
  surface.set_faces(b.F);
  const std::vector<float> short_rgb(3 * static_cast<size_t>(b.ev->points()) - 1, 0.5f);
  CHECK_THROWS_WITH(surface.draw(*b.ev, {.colors = short_rgb}),
                    Catch::StartsWith("Surface: " + std::to_string(short_rgb.size()) + " colour values for "));
  b.ev->evaluate(b.pipe->bezier_with(pl::Method::ModifiedBI), false);  // a pass without normals
  CHECK_THROWS_WITH(surface.draw(*b.ev), "Surface: normals asked of a pass without them");
  CHECK(glGetError() == GL_NO_ERROR);
}

TEST_CASE("gpu: the renderer's colours per point cover the surface it drew, its wireframe stays in front",
          "[gpu][render]") {
  TwistedBar b = twisted_bar();
  const int w = 200, h = 150;
  gpu::Renderer r(context());
  r.set_faces(b.F);
  const raster::View view = bar_view(b);
  const Eigen::Matrix4d vp = gpu::Renderer::view_matrix(view, w, h);
  std::vector<float> red;
  for (long long i = 0; i < b.ev->points(); ++i) red.insert(red.end(), {1.0f, 0.0f, 0.0f});
  const Target target(w, h);
  glClearColor(1, 1, 1, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  r.draw(*b.ev, vp, view.direction, {0.85, 0.62, 0.35}, &b.X, &b.T);
  r.draw_colors(*b.ev, vp, view.direction, red);
  const io::Image img = gpu::read_picture(w, h);
  long long reds = 0, greys = 0, others = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const auto* px = img.at(x, y);
      if (px[0] == 255 && px[1] == 255 && px[2] == 255) continue;
      if (px[0] > 0 && px[1] == 0 && px[2] == 0) ++reds;
      else if (px[0] == px[1] && px[1] == px[2]) ++greys;  // the wireframe's dark grey
      else ++others;
    }
  CHECK(reds > w * h / 10);
  CHECK(greys > 100);
  CHECK(others == 0);
  CHECK(glGetError() == GL_NO_ERROR);
}

TEST_CASE("gpu: the renderer's ground lies where its plane is, the shadow darkens it, its edge fades into the "
          "background", "[gpu][render]") {
  context();
  gpu::Renderer r(context());
  const int w = 200, h = 200;
  // seen from above: world x right, world z up the picture, 2 units across the picture's half
  Eigen::Matrix4d vp = Eigen::Matrix4d::Zero();
  vp(0, 0) = 0.5, vp(1, 2) = 0.5, vp(2, 1) = -0.1, vp(3, 3) = 1;
  gpu::Ground g;  // centre 0, e1 x, e2 z, half side 1, grid every 1
  g.shadow_center = {0.3, 0.3};
  g.shadow_half = {0.1, 0.1};
  g.shadow_soft = 0.05;
  g.background = {0, 0, 1};
  const Target target(w, h);
  glClearColor(1, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  r.draw_ground(g, vp);
  const io::Image img = gpu::read_picture(w, h);
  glDisable(GL_DEPTH_TEST);
  // the plane point (x, z) at pixel (100 + 50 x, 100 - 50 z)
  auto at = [&](double x, double z) { return img.at(int(100 + 50 * x), int(100 - 50 * z)); };
  const auto* outside = at(1.5, 1.5);  // beyond the square: not drawn
  CHECK((outside[0] == 255 && outside[1] == 0 && outside[2] == 0));
  const auto* faded = at(0.9, 0.9);  // in the square, past the fade: the background
  CHECK((faded[0] < 3 && faded[1] < 3 && faded[2] > 252));
  const auto* lit = at(-0.3, 0.3);
  const auto* shaded = at(0.3, 0.3);
  CHECK(lit[0] > 200);
  CHECK(std::abs(int(lit[0]) - int(lit[1])) < 4);  // the ground's grey
  CHECK(shaded[0] < 0.7 * lit[0]);
  CHECK(glGetError() == GL_NO_ERROR);
}

TEST_CASE("gpu: the renderer's ground refuses values it cannot draw, the material a pass without normals, the "
          "window helpers negative sizes", "[gpu]") {
  TwistedBar b = twisted_bar();
  gpu::Renderer r(context());
  r.set_faces(b.F);
  const Eigen::Matrix4d vp = Eigen::Matrix4d::Identity();
  auto refused = [&](auto change, const std::string& message) {
    gpu::Ground g;
    change(g);
    CHECK_THROWS_WITH(r.draw_ground(g, vp), "Renderer::draw_ground: " + message);
  };
  refused([](gpu::Ground& g) { g.center.x() = std::nan(""); }, "center is not finite");
  refused([](gpu::Ground& g) { g.half = 0; }, "half must be positive and finite, not 0");
  refused([](gpu::Ground& g) { g.spacing = -1; }, "spacing must be positive and finite, not -1");
  refused([](gpu::Ground& g) { g.shadow_soft = INFINITY; }, "shadow_soft must be positive and finite, not inf");
  refused([](gpu::Ground& g) { g.shadow_half = {0.1, -0.1}; }, "shadow_half must not be negative");
  refused([](gpu::Ground& g) { g.e1 *= 2; }, "e1 and e2 must be unit vectors");
  b.ev->evaluate(b.pipe->bezier_with(pl::Method::ModifiedBI), false);  // a pass without normals
  CHECK_THROWS_WITH(r.draw_material(*b.ev, vp, Eigen::Matrix3d::Identity(), {1, 1, 1}),
                    "Renderer: needs a 3D evaluation with normals");
  CHECK_THROWS_WITH(gpu::viewport(0, 0, -1, 2), "viewport: negative size -1 x 2");
  CHECK_THROWS_WITH(gpu::clear_window(3, -2, {1, 1, 1}), "clear_window: negative size 3 x -2");
  CHECK_THROWS_WITH(gpu::read_picture(-4, 1), "read_picture: negative size -4 x 1");
  CHECK(glGetError() == GL_NO_ERROR);
}

TEST_CASE("gpu: the renderer's material covers the surface draw() covers, in front of it", "[gpu][render]") {
  TwistedBar b = twisted_bar();
  const int w = 200, h = 150;
  gpu::Renderer r(context());
  r.set_faces(b.F);
  const raster::View view = bar_view(b);
  const Eigen::Matrix4d vp = gpu::Renderer::view_matrix(view, w, h);
  Eigen::Matrix3d rotation;  // world -> camera: right, up, toward the eye
  rotation.row(2) = -view.direction.normalized().transpose();
  rotation.row(0) = view.direction.cross(view.up).normalized().transpose();
  rotation.row(1) = rotation.row(2).cross(rotation.row(0));
  const Target target(w, h);
  auto picture = [&](bool surface, bool material) {
    glClearColor(1, 1, 1, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (surface) r.draw(*b.ev, vp, view.direction, {0.1, 0.8, 0.1});
    if (material) r.draw_material(*b.ev, vp, rotation, {0.85, 0.62, 0.35});
    glDisable(GL_DEPTH_TEST);
    return gpu::read_picture(w, h);
  };
  const io::Image surface = picture(true, false), material = picture(false, true), both = picture(true, true);
  CHECK(covered(material) > w * h / 10);
  CHECK(covered(material) == covered(surface));
  CHECK(both.rgb == material.rgb);  // nothing of draw()'s green shows through
  CHECK(glGetError() == GL_NO_ERROR);
}
