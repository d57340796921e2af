// FramePipeline (see frame_pipeline.hpp): a driver, the methods' Precompute and an evaluator.
#include <mbi/base/timer.hpp>
#include <mbi/error.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/pipeline/precompute.hpp>

#include <memory>

namespace mbi::pipeline {

struct FramePipeline::Impl {
  Precompute pre;
  std::shared_ptr<const interp::Embedding> embedding;
  std::unique_ptr<Driver> driver;
  PipelineOptions options;
  std::unique_ptr<Evaluator> evaluator;

  int frame = -1;
  Eigen::MatrixXd X;
  interp::VertexMatrices M;        // the method's M
  interp::VertexMatrices M_mbi;    // modified-BI's M at X (cached per frame)
  bool have_mbi = false;
  interp::VertexMatrices M_phong;  // Phong's M at X (cached per frame)
  bool have_phong = false;
  interp::BezierPoints B;
  bool evaluated = false;
  FrameTimings timings;

  // Method::BI builds nothing yet: the constructor builds what the method and driver need
  Impl(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
       const PipelineOptions& o)
      : pre(U, T, Method::BI, o.interp), options(o) {}

  // Phong's M at X: closed form from the element deformation gradients.
  const interp::VertexMatrices& phong_M() {
    if (!have_phong) {
      M_phong = pre.M(Method::Phong, X);
      have_phong = true;
    }
    return M_phong;
  }

  // Modified-BI's M at X: the driver's (joint solve) or the cached factorisation's.
  const interp::VertexMatrices& mbi_M() {
    if (!have_mbi) {
      if (const interp::VertexMatrices* dm = driver->solved_M())
        M_mbi = *dm;
      else
        M_mbi = pre.M(Method::ModifiedBI, X);
      have_mbi = true;
    }
    return M_mbi;
  }

  // The method's M and Bezier points for the current X.
  void solve_and_bezier() {
    auto t0 = Clock::now();
    const Method method = options.method;
    if (method == Method::BI) {
      const Eigen::Index nd = pre.rest_positions().size(), d = pre.dim();
      if (M.rows() != nd || M.cols() != d || M.any()) M.setZero(nd, d);  // BI: M = 0, set once
    } else {
      M = method == Method::Phong ? phong_M() : mbi_M();
    }
    timings.solve_ms = method == Method::BI || (method == Method::ModifiedBI && driver->solved_M()) ? 0.0 : ms_since(t0);
    t0 = Clock::now();
    B = pre.bezier(method, X, M);
    timings.bezier_ms = ms_since(t0);
  }

  void run_evaluator() {
    const auto t0 = Clock::now();
    evaluator->evaluate(B, options.normals);
    timings.evaluate_ms = ms_since(t0);
    evaluated = true;
  }
};

FramePipeline::FramePipeline(const Eigen::Ref<const Eigen::MatrixXd>& U,
                             const Eigen::Ref<const Eigen::MatrixXi>& T,
                             interp::Embedding embedding, std::unique_ptr<Driver> driver,
                             const PipelineOptions& options, std::unique_ptr<Evaluator> evaluator,
                             const Eigen::MatrixXd& rest_normals)
    : impl_(std::make_unique<Impl>(U, T, options)) {
  const int d = static_cast<int>(U.cols());
  if (embedding.size() > 0 && embedding.dim() != d)
    throw Error("the embedding is " + std::to_string(embedding.dim()) +
                "D, the control mesh " + std::to_string(d) + "D");
  if (!driver) throw Error("no driver");
  if (options.normals && rest_normals.size() == 0)
    throw Error("normals asked for, but no rest normals were given");
  Impl& s = *impl_;
  s.embedding = std::make_shared<const interp::Embedding>(std::move(embedding));
  s.driver = std::move(driver);
  s.evaluator = evaluator ? std::move(evaluator) : std::make_unique<CpuEvaluator>();
  const Eigen::MatrixXd& U0 = s.pre.rest_positions();
  const Eigen::MatrixXi& T0 = s.pre.elements();
  PointSet points;
  points.embedding = s.embedding;
  points.rest_bezier = interp::bezier_bi(U0, T0);
  points.rest_positions = s.embedding->size() > 0 ? interp::embedded_positions(U0, T0, *s.embedding)
                                                  : Eigen::MatrixXd(0, d);
  points.rest_normals = rest_normals;
  s.evaluator->set_points(points);
  s.X = U0;
  if (needs_solve(options.method) && !s.driver->solved_M()) s.pre.solver();
  if (needs_phong(options.method)) s.pre.phong();
}

FramePipeline::~FramePipeline() = default;
FramePipeline::FramePipeline(FramePipeline&&) noexcept = default;
FramePipeline& FramePipeline::operator=(FramePipeline&&) noexcept = default;

FrameResult FramePipeline::step(bool evaluate_now) {
  Impl& s = *impl_;
  const int next = s.frame + 1;
  Eigen::MatrixXd X;
  auto t0 = Clock::now();
  const DriveResult r = s.driver->drive(next, X);
  if (!r.ok) return {false, r.message, s.frame};
  s.timings = {};
  s.timings.drive_ms = ms_since(t0);
  s.pre.check_pose(X);
  s.X = std::move(X);
  s.frame = next;
  s.have_mbi = false;
  s.have_phong = false;
  s.evaluated = false;
  s.solve_and_bezier();
  if (evaluate_now) s.run_evaluator();
  return {true, {}, s.frame};
}

void FramePipeline::evaluate() {
  Impl& s = *impl_;
  if (s.frame < 0) throw Error("evaluate() before the first step()");
  if (!s.evaluated) s.run_evaluator();
}

void FramePipeline::reset() {
  Impl& s = *impl_;
  s.driver->reset();
  s.frame = -1;
  s.X = s.pre.rest_positions();
  s.have_mbi = false;
  s.have_phong = false;
  s.evaluated = false;
  s.timings = {};
}

int FramePipeline::frame() const { return impl_->frame; }
const Eigen::MatrixXd& FramePipeline::control_positions() const { return impl_->X; }
const interp::VertexMatrices& FramePipeline::M() const { return impl_->M; }
const interp::BezierPoints& FramePipeline::bezier() const { return impl_->B; }

const Eigen::MatrixXd& FramePipeline::positions() {
  evaluate();
  return impl_->evaluator->positions();
}

const Eigen::MatrixXd& FramePipeline::normals() {
  evaluate();
  return impl_->evaluator->normals();
}

const FrameTimings& FramePipeline::timings() const { return impl_->timings; }

const interp::VertexMatrices& FramePipeline::modified_bi_M() {
  if (impl_->frame < 0) throw Error("modified_bi_M() before the first step()");
  return impl_->mbi_M();
}

const interp::VertexMatrices& FramePipeline::phong_M() {
  if (impl_->frame < 0) throw Error("phong_M() before the first step()");
  return impl_->phong_M();
}

void FramePipeline::evaluate_with(Method method, Eigen::MatrixXd& out) {
  Impl& s = *impl_;
  if (s.frame < 0) throw Error("evaluate_with() before the first step()");
  if (method == s.options.method) {
    out = positions();
    return;
  }
  interp::evaluate<double>(bezier_with(method), *s.embedding, out);
}

interp::BezierPoints FramePipeline::bezier_with(Method method) {
  Impl& s = *impl_;
  if (s.frame < 0) throw Error("bezier_with() before the first step()");
  if (method == s.options.method) return s.B;
  if (method == Method::BI) return s.pre.bezier(method, s.X);
  return s.pre.bezier(method, s.X, method == Method::Phong ? s.phong_M() : s.mbi_M());
}

Method FramePipeline::method() const { return impl_->options.method; }

void FramePipeline::set_method(Method method) {
  Impl& s = *impl_;
  if (method == s.options.method) return;
  s.options.method = method;
  if (s.frame >= 0) {
    s.solve_and_bezier();
    s.evaluated = false;
  }
}

void FramePipeline::set_alpha(double alpha) {
  Impl& s = *impl_;
  s.pre.set_alpha(alpha);
  s.options.interp = s.pre.options();
  if (s.frame >= 0 && !s.driver->solved_M()) {
    s.have_mbi = false;
    s.solve_and_bezier();
    s.evaluated = false;
  }
}

const PipelineOptions& FramePipeline::options() const { return impl_->options; }
const interp::ModifiedBI& FramePipeline::solver() { return impl_->pre.solver(); }
double FramePipeline::precompute_ms() const { return impl_->pre.precompute_ms(); }
const interp::Phong& FramePipeline::phong() { return impl_->pre.phong(); }
double FramePipeline::phong_precompute_ms() const { return impl_->pre.phong_ms(); }
Driver& FramePipeline::driver() { return *impl_->driver; }

std::unique_ptr<Driver> FramePipeline::set_driver(std::unique_ptr<Driver> driver) {
  if (!driver) throw Error("no driver");
  std::swap(impl_->driver, driver);
  impl_->have_mbi = false;
  if (needs_solve(impl_->options.method) && !impl_->driver->solved_M()) impl_->pre.solver();
  return driver;
}
Evaluator& FramePipeline::evaluator() { return *impl_->evaluator; }
const interp::Embedding& FramePipeline::embedding() const { return *impl_->embedding; }
const Eigen::MatrixXd& FramePipeline::rest_positions() const { return impl_->pre.rest_positions(); }
const Eigen::MatrixXi& FramePipeline::elements() const { return impl_->pre.elements(); }
int FramePipeline::dim() const { return impl_->pre.dim(); }

}  // namespace mbi::pipeline
