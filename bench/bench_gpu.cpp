// CPU vs GPU interpolation of the same frame: p dense points in a box control mesh of 448
// vertices (1,764 tetrahedra), twisted, modified-BI. GPU: the transform-feedback evaluator on
// whatever OpenGL is present (Mesa llvmpipe on a machine without a GPU; the renderer string is
// the "renderer" label), timed per pass with the per-frame upload of the Bezier points
// (upload_ms) and without it (pass_ms); on llvmpipe a CPU clock around glFinish, on a GPU a timer
// query. CPU: the multithreaded kernel, float, all threads.
//
//   build/release/mbi-bench --benchmark_filter=Gpu
#include <mbi/generate/procedural.hpp>
#include <mbi/gpu/evaluator.hpp>
#include <mbi/interp.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <random>

namespace {

namespace pl = mbi::pipeline;

struct Setup {
  Eigen::MatrixXd U, X, P;
  Eigen::MatrixXi T;
};

const Setup& setup(long long p) {
  static std::map<long long, std::unique_ptr<Setup>> cache;
  auto& slot = cache[p];
  if (slot) return *slot;
  slot = std::make_unique<Setup>();
  Setup& s = *slot;
  mbi::generate::box_tets(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 1, 4), Eigen::Vector3i(7, 7, 6), s.U, s.T);
  s.X = mbi::generate::twist_bend(s.U, 0.5, 0.5, 0, 4, 1.2, 0.1);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(0.001, 0.999);
  s.P.resize(p, 3);
  for (long long i = 0; i < p; ++i) s.P.row(i) << uni(rng), uni(rng), 4 * uni(rng);
  return s;
}

std::unique_ptr<pl::FramePipeline> pipeline_for(const Setup& s, std::unique_ptr<pl::Evaluator> ev) {
  auto d = std::make_unique<pl::GivenDriver>(s.U);
  d->set(s.X);
  return std::make_unique<pl::FramePipeline>(s.U, s.T, mbi::interp::embed(s.U, s.T, s.P), std::move(d),
                                             pl::PipelineOptions{}, std::move(ev));
}

mbi::gpu::Context* context(std::string& why) {
  static std::unique_ptr<mbi::gpu::Context> c;
  static std::string error;
  if (!c && error.empty()) {
    try {
      c = mbi::gpu::Context::headless();
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  why = error;
  return c.get();
}

void BM_GpuEvaluate(benchmark::State& st) {
  std::string why;
  mbi::gpu::Context* ctx = context(why);
  if (!ctx) {
    st.SkipWithError(why.c_str());
    return;
  }
  const Setup& s = setup(st.range(0));
  auto pipe = pipeline_for(s, std::make_unique<mbi::gpu::GpuEvaluator>(*ctx));
  pipe->step(false);  // drive + solve + Bezier once; the loop times the evaluator alone
  const mbi::interp::BezierPoints B = pipe->bezier();
  auto& ev = pipe->evaluator();
  double upload = 0, pass = 0;
  for (auto _ : st) {
    ev.evaluate(B, false);
    upload += ev.timings().upload_ms;
    pass += ev.timings().pass_ms;
  }
  const double n = static_cast<double>(st.iterations());
  st.counters["upload_ms"] = upload / n;
  st.counters["pass_ms"] = pass / n;
  st.counters["points"] = static_cast<double>(s.P.rows());
  st.SetLabel(ctx->renderer());
  st.SetItemsProcessed(st.iterations() * s.P.rows());
}

void BM_GpuCpuEvaluate(benchmark::State& st) {
  const Setup& s = setup(st.range(0));
  auto pipe = pipeline_for(s, std::make_unique<pl::CpuEvaluator>(pl::Precision::Float));
  pipe->step(false);
  const mbi::interp::BezierPoints B = pipe->bezier();
  auto& ev = pipe->evaluator();
  for (auto _ : st) ev.evaluate(B, false);
  st.counters["points"] = static_cast<double>(s.P.rows());
  st.SetLabel(ev.name());
  st.SetItemsProcessed(st.iterations() * s.P.rows());
}

}  // namespace

BENCHMARK(BM_GpuEvaluate)->Arg(35000)->Arg(250000)->Arg(1000000)->Arg(4000000)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(0.5);
BENCHMARK(BM_GpuCpuEvaluate)->Arg(35000)->Arg(250000)->Arg(1000000)->Arg(4000000)
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(0.5);
