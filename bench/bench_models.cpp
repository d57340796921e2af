// The paper's Table 1 on our models: precompute (assembly + sparse Cholesky factorisation, the
// interp::ModifiedBI constructor), per-frame solve of all M_i, CPU evaluation (our kernel, float,
// positions) and GPU evaluation (the transform-feedback evaluator, per-frame upload included)
// of the dense points from the frame's modified-BI Bezier points. Models:
//   bar    the paper's bar (Figure 1): 23,402 vertices in 35 control vertices
//   large  scenes/large.toml: a 252,152-vertex bumpy sphere in its generated ~450-vertex cage
//          (full run only)
//   bunny  $MBI_MODELS_DIR/stanford-bunny.obj (35,947 vertices) in generate::make_cage with a
//          target of 103 control vertices, as in the paper; skipped without MBI_MODELS_DIR
// The control mesh is twisted (a smooth non-affine pose) for the solve and the evaluations.
//
//   MBI_MODELS_DIR=../shared/models build/release/mbi-bench --benchmark_filter=Table1
#include "bench_common.hpp"

#include <mbi/generate/cage.hpp>
#include <mbi/gpu/evaluator.hpp>
#include <mbi/interp/fast_evaluate.hpp>
#include <mbi/io/io.hpp>
#include <mbi/scenes/runner.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <thread>

namespace {

struct Model {
  Eigen::MatrixXd V, U, X;  // dense rest, control rest, control deformed
  Eigen::MatrixXi T;
  std::shared_ptr<const mbi::interp::Embedding> emb;
  std::unique_ptr<mbi::interp::ModifiedBI> solver;
  mbi::interp::BezierPoints B;  // modified-BI at X
  std::string error;
};

// Twist about the vertical (y) axis through the centre of the bounding box, plus a mild bend.
Eigen::MatrixXd twist_y(const Eigen::MatrixXd& U) {
  const Eigen::RowVector3d lo = U.colwise().minCoeff(), hi = U.colwise().maxCoeff();
  const Eigen::RowVector3d c = 0.5 * (lo + hi);
  Eigen::MatrixXd X = U;
  const double pi = std::acos(-1.0);
  for (Eigen::Index i = 0; i < U.rows(); ++i) {
    const double s = (U(i, 1) - lo.y()) / (hi.y() - lo.y());
    const double th = 0.5 * pi * s;
    const double x = U(i, 0) - c.x(), z = U(i, 2) - c.z();
    X(i, 0) = c.x() + std::cos(th) * x - std::sin(th) * z + 0.1 * s * s * (hi.y() - lo.y());
    X(i, 2) = c.z() + std::sin(th) * x + std::cos(th) * z;
  }
  return X;
}

const Model& model(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Model>> cache;
  auto& slot = cache[name];
  if (slot) return *slot;
  slot = std::make_unique<Model>();
  Model& m = *slot;
  try {
    if (name == "bar") {
      Eigen::MatrixXi F;
      mbi::generate::paper_bar_surface(m.V, F);
      mbi::generate::paper_bar_control(m.U, m.T);
      m.X = mbi::generate::twist_bend(m.U, 0, 0, 0, 6, std::acos(-1.0) / 2, 0.05);
    } else if (name == "large") {
      const auto scene = mbi::scenes::load_scene(std::filesystem::path(MBI_SOURCE_DIR) / "scenes/large.toml");
      const auto models = mbi::scenes::load_models(scene);
      m.V = models.dense.V;
      m.U = models.U;
      m.T = models.T;
      m.X = twist_y(m.U);
    } else {
      const char* dir = std::getenv("MBI_MODELS_DIR");
      if (!dir) {
        m.error = "MBI_MODELS_DIR is not set";
        return m;
      }
      const auto surf = mbi::io::read_surface(std::filesystem::path(dir) / "stanford-bunny.obj");
      m.V = surf.V;
      mbi::generate::CageOptions o;
      o.target_vertices = 103;
      const auto cage = mbi::generate::make_cage(surf.V, surf.F, o);
      m.U = cage.U;
      m.T = cage.T;
      m.X = twist_y(m.U);
    }
    m.emb = std::make_shared<mbi::interp::Embedding>(mbi::interp::embed(m.U, m.T, m.V));
    m.solver = std::make_unique<mbi::interp::ModifiedBI>(m.U, m.T);
    m.B = m.solver->bezier(m.X, m.solver->solve(m.X));
  } catch (const std::exception& e) {
    m.error = e.what();
  }
  return m;
}

bool ready(benchmark::State& st, const Model& m) {
  if (!m.error.empty()) {
    st.SkipWithError(m.error.c_str());
    return false;
  }
  st.counters["dense"] = static_cast<double>(m.V.rows());
  st.counters["control"] = static_cast<double>(m.U.rows());
  st.counters["tets"] = static_cast<double>(m.T.rows());
  return true;
}

void BM_Table1Precompute(benchmark::State& st, const std::string& name) {
  const Model& m = model(name);
  if (!ready(st, m)) return;
  for (auto _ : st) {
    mbi::interp::ModifiedBI s(m.U, m.T);
    benchmark::DoNotOptimize(s.beta());
  }
}

void BM_Table1Solve(benchmark::State& st, const std::string& name) {
  const Model& m = model(name);
  if (!ready(st, m)) return;
  for (auto _ : st) {
    mbi::interp::VertexMatrices M = m.solver->solve(m.X);
    benchmark::DoNotOptimize(M.data());
  }
}

// Argument: threads (0 = all).
void BM_Table1Cpu(benchmark::State& st, const std::string& name) {
  const Model& m = model(name);
  if (!ready(st, m)) return;
  const int threads = static_cast<int>(st.range(0));
  // the kernel the pipeline's float CPU evaluator runs
  mbi::interp::FastEvaluator fe(*m.emb, threads);
  mbi::interp::RowMatrixXf pos;
  for (auto _ : st) {
    fe.evaluate(m.B, pos);
    benchmark::DoNotOptimize(pos.data());
  }
  st.counters["threads"] = fe.threads();
}

void BM_Table1Gpu(benchmark::State& st, const std::string& name) {
  std::string why;
  mbi::gpu::Context* ctx = mbi::bench::gl_context(why);
  if (!ctx) {
    st.SkipWithError(("no OpenGL: " + why).c_str());
    return;
  }
  const Model& m = model(name);
  if (!ready(st, m)) return;
  mbi::gpu::GpuEvaluator ev(*ctx);
  mbi::pipeline::PointSet points;
  points.embedding = m.emb;
  points.rest_bezier = mbi::interp::bezier_bi(m.U, m.T);
  points.rest_positions = m.V;
  ev.set_points(points);
  double upload = 0, pass = 0;
  for (auto _ : st) {
    ev.evaluate(m.B, false);
    upload += ev.timings().upload_ms;
    pass += ev.timings().pass_ms;
  }
  const double n = static_cast<double>(st.iterations());
  st.counters["upload_ms"] = upload / n;
  st.counters["pass_ms"] = pass / n;
  st.SetLabel(ctx->renderer());
}

[[maybe_unused]] const bool registered = [] {
  for (const char* name : {"bar", "large", "bunny"}) {
    if (mbi::bench::quick() && std::string(name) == "large") continue;
    const double t = mbi::bench::min_time(0.3);
    const std::string n(name);
    benchmark::RegisterBenchmark(("BM_Table1Precompute/" + n).c_str(), BM_Table1Precompute, n)
        ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(t);
    benchmark::RegisterBenchmark(("BM_Table1Solve/" + n).c_str(), BM_Table1Solve, n)
        ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(t);
    benchmark::RegisterBenchmark(("BM_Table1Cpu/" + n).c_str(), BM_Table1Cpu, n)
        ->ArgName("threads")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(t);
    benchmark::RegisterBenchmark(("BM_Table1Gpu/" + n).c_str(), BM_Table1Gpu, n)
        ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(t);
  }
  return true;
}();

}  // namespace
