// One whole frame of each shipped scene through the frame pipeline (the runner's own set-up:
// scenes::make_pipeline): drive (simulation step or handle solve) + solve M + Bezier points +
// CPU evaluation in double, as `mbi run` does it, without writing files. The counters give the
// mean time of each phase in ms. The scene restarts from its first frame when it reaches its
// last, so every frame measured is one that `mbi run` computes.
//
//   build/release/mbi-bench --benchmark_filter=Frame
#include "bench_common.hpp"

#include <mbi/scenes/runner.hpp>

#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <memory>

namespace {

struct SceneState {
  mbi::scenes::Scene scene;
  mbi::scenes::SceneModels models;
  std::unique_ptr<mbi::pipeline::FramePipeline> pipe;
};

std::filesystem::path scene_file(const std::string& name) {
  return std::filesystem::path(MBI_SOURCE_DIR) / "scenes" / (name + ".toml");
}

void BM_SceneFrame(benchmark::State& st, const std::string& name) {
  SceneState s;
  s.scene = mbi::scenes::load_scene(scene_file(name));
  s.models = mbi::scenes::load_models(s.scene);
  s.pipe = std::make_unique<mbi::pipeline::FramePipeline>(mbi::scenes::make_pipeline(
      s.scene, s.models, mbi::interp::embed(s.models.U, s.models.T, s.models.dense.V)));
  mbi::pipeline::FramePipeline& pipe = *s.pipe;
  const int last = s.scene.simulation.frames;
  pipe.step();  // frame 0
  mbi::pipeline::FrameTimings sum;
  for (auto _ : st) {
    if (pipe.frame() >= last) {
      st.PauseTiming();
      pipe.reset();
      pipe.step();
      st.ResumeTiming();
    }
    if (!pipe.step().ok) {
      st.SkipWithError("a simulation step failed");
      return;
    }
    const auto& t = pipe.timings();
    sum.drive_ms += t.drive_ms;
    sum.solve_ms += t.solve_ms;
    sum.bezier_ms += t.bezier_ms;
    sum.evaluate_ms += t.evaluate_ms;
  }
  const double n = static_cast<double>(st.iterations());
  st.counters["drive_ms"] = sum.drive_ms / n;
  st.counters["solve_ms"] = sum.solve_ms / n;
  st.counters["bezier_ms"] = sum.bezier_ms / n;
  st.counters["evaluate_ms"] = sum.evaluate_ms / n;
  st.counters["dense"] = static_cast<double>(s.models.dense.V.rows());
  st.counters["control"] = static_cast<double>(s.models.U.rows());
}

// Quick mode (CI): every scene but `large`.
[[maybe_unused]] const bool registered = [] {
  for (const char* name : {"twist-bar", "cantilever", "poke", "drag", "image-warp", "large"}) {
    if (mbi::bench::quick() && std::string(name) == "large") continue;
    benchmark::RegisterBenchmark((std::string("BM_SceneFrame/") + name).c_str(), BM_SceneFrame,
                                 std::string(name))
        ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(mbi::bench::min_time(0.5));
  }
  return true;
}();

}  // namespace
