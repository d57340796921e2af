// Embed / precompute / solve / one whole frame (solve + Bezier + float evaluation, through the
// frame pipeline) on real models (paper Table 1): the Stanford bunny
// (35,947 vertices) in generated control meshes of about 100 and 450 vertices, and the paper's
// bar (23,402 vertices in 35). Real models come from $MBI_MODELS_DIR; without it the bunny
// benchmarks report an error and are skipped.
//
//   MBI_MODELS_DIR=../shared/models build/release/mbi-bench --benchmark_filter=Model
#include <mbi/generate/cage.hpp>
#include <mbi/generate/procedural.hpp>
#include <mbi/interp.hpp>
#include <mbi/io/io.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>

namespace {

struct Model {
  Eigen::MatrixXd V, U, X;  // dense rest, control rest, control deformed
  Eigen::MatrixXi T;
  std::string error;
};

// Twist about the vertical (y) axis through the centre of the bounding box, plus a mild bend:
// a smooth non-affine deformation of the control mesh.
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

const Model& model(const std::string& name, int target) {
  static std::map<std::pair<std::string, int>, std::unique_ptr<Model>> cache;
  auto& slot = cache[{name, target}];
  if (slot) return *slot;
  slot = std::make_unique<Model>();
  Model& m = *slot;
  if (name == "bar") {
    Eigen::MatrixXi F;
    mbi::generate::paper_bar_surface(m.V, F);
    mbi::generate::paper_bar_control(m.U, m.T);
    m.X = mbi::generate::twist_bend(m.U, 0, 0, 0, 6, std::acos(-1.0) / 2, 0.05);
    return m;
  }
  const char* dir = std::getenv("MBI_MODELS_DIR");
  if (!dir) {
    m.error = "MBI_MODELS_DIR is not set";
    return m;
  }
  const auto surf = mbi::io::read_surface(std::filesystem::path(dir) / (name + ".obj"));
  m.V = surf.V;
  mbi::generate::CageOptions o;
  o.target_vertices = target;
  const auto cage = mbi::generate::make_cage(surf.V, surf.F, o);
  m.U = cage.U;
  m.T = cage.T;
  m.X = twist_y(m.U);
  return m;
}

void set_counters(benchmark::State& st, const Model& m) {
  st.counters["dense"] = static_cast<double>(m.V.rows());
  st.counters["control"] = static_cast<double>(m.U.rows());
  st.counters["tets"] = static_cast<double>(m.T.rows());
}

#define MODEL_OR_SKIP(st, name, target)          \
  const Model& m = model(name, target);          \
  if (!m.error.empty()) {                        \
    st.SkipWithError(m.error.c_str());           \
    return;                                      \
  }                                              \
  set_counters(st, m)

template <int Which>
void run(benchmark::State& st, const char* name) {
  const int target = static_cast<int>(st.range(0));
  MODEL_OR_SKIP(st, name, target);
  if constexpr (Which == 0) {  // embed
    for (auto _ : st) benchmark::DoNotOptimize(mbi::interp::embed(m.U, m.T, m.V));
  } else if constexpr (Which == 1) {  // precompute (assembly, beta, gauge, factorisation)
    for (auto _ : st) {
      mbi::interp::ModifiedBI s(m.U, m.T);
      benchmark::DoNotOptimize(s.beta());
    }
  } else if constexpr (Which == 2) {  // per-frame solve of all M_i
    const mbi::interp::ModifiedBI s(m.U, m.T);
    for (auto _ : st) benchmark::DoNotOptimize(s.solve(m.X));
  } else {  // one whole frame through the pipeline: given X -> solve -> Bezier -> evaluate
    namespace pl = mbi::pipeline;
    auto given = std::make_unique<pl::GivenDriver>(m.U);
    given->set(m.X);
    pl::FramePipeline pipe(m.U, m.T, mbi::interp::embed(m.U, m.T, m.V), std::move(given), {},
                           std::make_unique<pl::CpuEvaluator>(pl::Precision::Float));
    pl::FrameTimings sum;
    for (auto _ : st) {
      benchmark::DoNotOptimize(pipe.step().ok);
      sum.solve_ms += pipe.timings().solve_ms;
      sum.bezier_ms += pipe.timings().bezier_ms;
      sum.evaluate_ms += pipe.timings().evaluate_ms;
    }
    const double n = static_cast<double>(st.iterations());
    st.counters["solve_ms"] = sum.solve_ms / n;
    st.counters["bezier_ms"] = sum.bezier_ms / n;
    st.counters["evaluate_ms"] = sum.evaluate_ms / n;
  }
}

void BM_ModelBunnyEmbed(benchmark::State& st) { run<0>(st, "stanford-bunny"); }
void BM_ModelBunnyPrecompute(benchmark::State& st) { run<1>(st, "stanford-bunny"); }
void BM_ModelBunnySolve(benchmark::State& st) { run<2>(st, "stanford-bunny"); }
void BM_ModelBunnyFrame(benchmark::State& st) { run<3>(st, "stanford-bunny"); }
void BM_ModelBarEmbed(benchmark::State& st) { run<0>(st, "bar"); }
void BM_ModelBarPrecompute(benchmark::State& st) { run<1>(st, "bar"); }
void BM_ModelBarSolve(benchmark::State& st) { run<2>(st, "bar"); }
void BM_ModelBarFrame(benchmark::State& st) { run<3>(st, "bar"); }

}  // namespace

BENCHMARK(BM_ModelBarEmbed)->Arg(35)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ModelBarPrecompute)->Arg(35)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ModelBarSolve)->Arg(35)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_ModelBarFrame)->Arg(35)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ModelBunnyEmbed)->Arg(100)->Arg(450)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ModelBunnyPrecompute)->Arg(100)->Arg(450)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ModelBunnySolve)->Arg(100)->Arg(450)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_ModelBunnyFrame)->Arg(100)->Arg(450)->Unit(benchmark::kMillisecond)->UseRealTime();
