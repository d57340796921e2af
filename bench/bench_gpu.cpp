// CPU vs GPU interpolation of the same frame: p dense points (random, bench_common.hpp) in a box
// control mesh of 448 vertices (1,764 tetrahedra), twisted, modified-BI. GPU: the
// transform-feedback evaluator on whatever OpenGL is present (Mesa llvmpipe on a machine without
// a GPU; the renderer string is the label), timed per pass with the per-frame upload of the
// Bezier points (upload_ms) and without it (pass_ms); on llvmpipe a CPU clock around glFinish, on
// a GPU a timer query. CPU: the frame pipeline's CPU evaluator, float, all threads.
//
//   build/release/mbi-bench --benchmark_filter=Gpu
#include "bench_common.hpp"

#include <mbi/gpu/evaluator.hpp>
#include <mbi/pipeline/evaluator.hpp>

#include <benchmark/benchmark.h>

#include <memory>

namespace {

namespace pl = mbi::pipeline;

constexpr int kControl = 450;

// The evaluator with the points of a p-point cloud set.
void set_points(pl::Evaluator& ev, long long p) {
  const mbi::bench::Cage& cage = mbi::bench::box_cage(kControl);
  const mbi::bench::Cloud& c = mbi::bench::cloud(kControl, p);
  pl::PointSet points;
  points.embedding = std::make_shared<const mbi::interp::Embedding>(c.emb);
  points.rest_bezier = mbi::interp::bezier_bi(cage.U, cage.T);
  points.rest_positions = c.P;
  ev.set_points(points);
}

void BM_GpuEvaluate(benchmark::State& st) {
  std::string why;
  mbi::gpu::Context* ctx = mbi::bench::gl_context(why);
  if (!ctx) {
    st.SkipWithError(("no OpenGL: " + why).c_str());
    return;
  }
  const long long p = st.range(0);
  mbi::gpu::GpuEvaluator ev(*ctx);
  set_points(ev, p);
  const mbi::interp::BezierPoints& B = mbi::bench::box_cage(kControl).bezier_mbi;
  double upload = 0, pass = 0;
  for (auto _ : st) {
    ev.evaluate(B, false);
    upload += ev.timings().upload_ms;
    pass += ev.timings().pass_ms;
  }
  const double n = static_cast<double>(st.iterations());
  st.counters["upload_ms"] = upload / n;
  st.counters["pass_ms"] = pass / n;
  st.counters["points"] = static_cast<double>(p);
  st.SetLabel(ctx->renderer());
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations()) * p);
}

void BM_GpuCpuEvaluate(benchmark::State& st) {
  const long long p = st.range(0);
  pl::CpuEvaluator ev(pl::Precision::Float);
  set_points(ev, p);
  const mbi::interp::BezierPoints& B = mbi::bench::box_cage(kControl).bezier_mbi;
  for (auto _ : st) ev.evaluate(B, false);
  st.counters["points"] = static_cast<double>(p);
  st.SetLabel(ev.name());
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations()) * p);
}

void sizes(benchmark::internal::Benchmark* b) {
  b->ArgName("points");
  for (long long p : mbi::bench::point_counts()) b->Arg(p);
}

}  // namespace

BENCHMARK(BM_GpuEvaluate)->Apply(sizes)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time(0.5));
BENCHMARK(BM_GpuCpuEvaluate)->Apply(sizes)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->MinTime(mbi::bench::min_time(0.5));
