#include <mbi/base/timer.hpp>
#include <mbi/error.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include <chrono>

namespace mbi::pipeline {
namespace {

}  // namespace

struct FramePipeline::Impl {
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  std::shared_ptr<const interp::Embedding> embedding;
  std::unique_ptr<Driver> driver;
  PipelineOptions options;
  std::unique_ptr<Evaluator> evaluator;
  std::optional<interp::ModifiedBI> solver;
  double precompute_ms = 0;
  std::optional<interp::Phong> phong;
  double phong_ms = 0;

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

  const interp::ModifiedBI& get_solver() {
    if (!solver) {
      const auto t0 = Clock::now();
      solver.emplace(U, T, options.interp);
      precompute_ms = ms_since(t0);
    }
    return *solver;
  }

  const interp::Phong& get_phong() {
    if (!phong) {
      const auto t0 = Clock::now();
      phong.emplace(U, T);
      phong_ms = ms_since(t0);
    }
    return *phong;
  }

  // Phong's M at X: closed form from the element deformation gradients.
  const interp::VertexMatrices& phong_M() {
    if (!have_phong) {
      M_phong = get_phong().M(X);
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
        M_mbi = get_solver().solve(X);
      have_mbi = true;
    }
    return M_mbi;
  }

  // The method's M and Bezier points for the current X.
  void solve_and_bezier() {
    auto t0 = Clock::now();
    const int n = static_cast<int>(U.rows()), d = static_cast<int>(U.cols());
    if (options.method == Method::BI) {
      if (M.rows() != static_cast<Eigen::Index>(n) * d || M.cols() != d || M.any())
        M.setZero(static_cast<Eigen::Index>(n) * d, d);  // BI: M = 0, set once, not every frame
      timings.solve_ms = 0;
      t0 = Clock::now();
      B = interp::bezier_bi(X, T);
    } else if (options.method == Method::Phong) {
      M = phong_M();
      timings.solve_ms = ms_since(t0);
      t0 = Clock::now();
      B = interp::bezier_points(U, T, X, M);
    } else {
      M = mbi_M();
      timings.solve_ms = driver->solved_M() ? 0.0 : ms_since(t0);
      t0 = Clock::now();
      B = interp::bezier_points(U, T, X, M);
    }
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
    : impl_(std::make_unique<Impl>()) {
  const int d = static_cast<int>(U.cols());
  if ((d != 2 && d != 3) || T.cols() != d + 1)
    throw Error("the control mesh must be n x d (d = 2, 3) with m x (d+1) elements");
  if (embedding.size() > 0 && embedding.dim() != d)
    throw Error("the embedding is " + std::to_string(embedding.dim()) +
                "D, the control mesh " + std::to_string(d) + "D");
  if (!driver) throw Error("no driver");
  if (options.normals && rest_normals.size() == 0)
    throw Error("normals asked for, but no rest normals were given");
  Impl& s = *impl_;
  s.U = U;
  s.T = T;
  s.embedding = std::make_shared<const interp::Embedding>(std::move(embedding));
  s.driver = std::move(driver);
  s.options = options;
  s.evaluator = evaluator ? std::move(evaluator) : std::make_unique<CpuEvaluator>();
  PointSet points;
  points.embedding = s.embedding;
  points.rest_bezier = interp::bezier_bi(s.U, s.T);
  points.rest_positions = s.embedding->size() > 0 ? interp::embedded_positions(s.U, s.T, *s.embedding)
                                                  : Eigen::MatrixXd(0, d);
  points.rest_normals = rest_normals;
  s.evaluator->set_points(points);
  s.X = s.U;
  if (needs_solve(options.method) && !s.driver->solved_M()) s.get_solver();
  if (needs_phong(options.method)) s.get_phong();
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
  if (X.rows() != s.U.rows() || X.cols() != s.U.cols())
    throw Error("the driver gave " + std::to_string(X.rows()) + " x " +
                std::to_string(X.cols()) + " positions for a control mesh of " +
                std::to_string(s.U.rows()) + " x " + std::to_string(s.U.cols()));
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
  s.X = s.U;
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
  switch (method) {
    case Method::BI: return interp::bezier_bi(s.X, s.T);
    case Method::ModifiedBI: return interp::bezier_points(s.U, s.T, s.X, s.mbi_M());
    case Method::Phong: return interp::bezier_points(s.U, s.T, s.X, s.phong_M());
  }
  return s.B;
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
  if (!(alpha > 0)) throw Error("alpha must be > 0");
  s.options.interp.alpha = alpha;
  if (s.solver) {
    const auto t0 = Clock::now();
    s.solver->set_alpha(alpha);
    s.precompute_ms = ms_since(t0);
  }
  if (s.frame >= 0 && !s.driver->solved_M()) {
    s.have_mbi = false;
    s.solve_and_bezier();
    s.evaluated = false;
  }
}

const PipelineOptions& FramePipeline::options() const { return impl_->options; }
const interp::ModifiedBI& FramePipeline::solver() { return impl_->get_solver(); }
double FramePipeline::precompute_ms() const { return impl_->precompute_ms; }
const interp::Phong& FramePipeline::phong() { return impl_->get_phong(); }
double FramePipeline::phong_precompute_ms() const { return impl_->phong_ms; }
Driver& FramePipeline::driver() { return *impl_->driver; }

std::unique_ptr<Driver> FramePipeline::set_driver(std::unique_ptr<Driver> driver) {
  if (!driver) throw Error("no driver");
  std::swap(impl_->driver, driver);
  impl_->have_mbi = false;
  if (needs_solve(impl_->options.method) && !impl_->driver->solved_M()) impl_->get_solver();
  return driver;
}
Evaluator& FramePipeline::evaluator() { return *impl_->evaluator; }
const interp::Embedding& FramePipeline::embedding() const { return *impl_->embedding; }
const Eigen::MatrixXd& FramePipeline::rest_positions() const { return impl_->U; }
const Eigen::MatrixXi& FramePipeline::elements() const { return impl_->T; }
int FramePipeline::dim() const { return static_cast<int>(impl_->U.cols()); }

}  // namespace mbi::pipeline
