// Contact at the dense surface on the `large` scene (252,152 points): a frame with contact against
// the same frame without, both pipelines stepped side by side in one run, so that their ratio is
// measured under the same load. The scene is scenes/large.toml changed where contact needs it:
// damping_stiffness 0 (refused with contact), no poke, the top tenth of the control nodes fixed.
// The contact variant has contact = "surface" and a plane that starts at the model's lowest
// point and rises 0.1 m in the first 0.2 s, pressing into the ball (a cap of 0.1 m is 5% of a
// sphere's surface) with a soft penalty (kStiffness, kMaxDepth), so that about that much of the
// sagging surface is inside the plane; its frames are measured from frame 8 on. The plain variant has no contact
// and no ground. Both with the scene's method (modified-BI) and with BI, whose contact Hessian
// surrogate is exact against a plane; and modified-BI with Newton on that surrogate alone
// (`modified-bi-blocks`: the contact without its exact Hessian product). Counters: ms of each frame, their ratio, Newton
// and PCG iterations per frame of each, the contact frame's line-search halvings, the contact points
// inside the plane and their fraction of the surface, and the broad phase's counts
// (SurfaceContact::counts: candidates and points with a term per evaluation at a new x,
// candidates per move, points evaluated per substep start). Also at 20K and 1M points: the
// scene's bumpy sphere resampled in the scene's cage, the stiffness per point scaled to the same
// per area, so that the same fraction touches.
//
//   build/release/mbi-bench --benchmark_filter=ContactFrame
#include "bench_common.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/generate/procedural.hpp>
#include <mbi/scenes/models.hpp>

#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>
#include <string>
#include <utility>

namespace {

using mbi::pipeline::FramePipeline;
using mbi::pipeline::SimulatorDriver;

// N/m per contact point of the scene's 252,152 (the same per area for another number of points):
// soft enough that the plane sinks into the surface about as deep as it rises past the ball's
// lowest point, so that about 5% of the surface touches; the guarded depth (m) beyond that
// depth, so that the law is the penalty and not its barrier at the depth.
constexpr double kStiffness = 300.0, kMaxDepth = 0.3, kScenePoints = 252152;

mbi::scenes::Scene large_scene(mbi::pipeline::Method method, bool contact, double lowest, double points) {
  mbi::scenes::Scene sc = mbi::scenes::load_scene(std::filesystem::path(MBI_SOURCE_DIR) / "scenes" / "large.toml");
  sc.interpolation.method = method;
  mbi::sim::Parameters& p = sc.simulation.parameters;
  p.stiffness_damping = 0.0;
  p.ground = false;
  sc.pokes.clear();
  sc.constraints.resize(1);
  sc.constraints[0].select.box_relative = std::make_pair(Eigen::Vector3d(0, 0.9, 0), Eigen::Vector3d(1, 1, 1));
  if (contact) {
    sc.simulation.contact = mbi::pipeline::ContactMode::Surface;
    sc.simulation.contact_stiffness = kStiffness * kScenePoints / points;
    p.newton_iterations = mbi::scenes::kSurfaceNewtonIterations;
    mbi::pipeline::Collider plane = mbi::pipeline::Collider::plane({0, lowest, 0}, {0, 1, 0});
    plane.motion.velocity = {0, 0.5, 0};
    plane.motion.stop = 0.2;
    sc.colliders.push_back(plane);
  }
  return sc;
}

/// The contact without its Hessian product: Newton steps on the Hessian blocks alone.
struct BlocksOnly : mbi::sim::Potential {
  using Vec = Eigen::Ref<const Eigen::VectorXd>;
  std::shared_ptr<mbi::pipeline::SurfaceContact> c;
  explicit BlocksOnly(std::shared_ptr<mbi::pipeline::SurfaceContact> contact) : c(std::move(contact)) {}
  void begin_substep_at(double t0, double t1, const Vec& x, const Vec& v) override { c->begin_substep_at(t0, t1, x, v); }
  double max_step(const Vec& x, const Vec& dx) const override { return c->max_step(x, dx); }
  double energy(const Vec& x) const override { return c->energy(x); }
  void begin_line(const Vec& x, const Vec& dx) override { c->begin_line(x, dx); }
  double energy_along(double s) const override { return c->energy_along(s); }
  void add_gradient(const Vec& x, Eigen::Ref<Eigen::VectorXd> g) const override { c->add_gradient(x, g); }
  void hessian_blocks(const Vec& x, std::vector<mbi::sim::NodeBlock>& b) const override { c->hessian_blocks(x, b); }
};

struct Side {
  mbi::scenes::Scene scene;
  std::unique_ptr<FramePipeline> pipe;
  double ms = 0;
  long newton = 0, halvings = 0, pcg = 0;
  const SimulatorDriver& driver() { return dynamic_cast<const SimulatorDriver&>(pipe->driver()); }
  bool step() {
    const auto t0 = mbi::Clock::now();
    const bool ok = pipe->step().ok;
    ms += mbi::ms_since(t0);
    newton += driver().last_step().newton_iterations;
    halvings += driver().last_step().line_search_halvings;
    pcg += driver().last_step().solver_iterations;
    return ok;
  }
};

/// resolution: the bumpy sphere's (6 n^2 + 2 points; the scene's is 205), in the scene's own cage.
void BM_ContactFrame(benchmark::State& st, mbi::pipeline::Method method, bool blocks_only, int resolution) {
  const mbi::scenes::Scene plain_scene = large_scene(method, false, 0.0, 0.0);
  mbi::scenes::SceneModels m = mbi::scenes::load_models(plain_scene);
  mbi::generate::bumpy_sphere(1.0, resolution, 0.05, m.dense.V, m.dense.F);
  m.dense.N.resize(0, 0);
  const double lowest = m.dense.V.col(1).minCoeff();
  Side with{large_scene(method, true, lowest, static_cast<double>(m.dense.V.rows())), nullptr}, without{plain_scene, nullptr};
  for (Side* s : {&with, &without})
    s->pipe = std::make_unique<FramePipeline>(
        mbi::scenes::make_pipeline(s->scene, m, mbi::interp::embed(m.U, m.T, m.dense.V)));
  with.driver().contact()->set_max_depth(kMaxDepth);
  if (blocks_only)
    dynamic_cast<SimulatorDriver&>(with.pipe->driver()).simulator().set_potential(
        std::make_shared<BlocksOnly>(with.driver().contact()));
  for (int f = 0; f < 8; ++f)  // the plane rises into the ball in frames 1..6
    if (!with.pipe->step().ok || !without.pipe->step().ok) return st.SkipWithError("a step failed while warming up");
  with.ms = without.ms = 0;
  with.newton = without.newton = with.halvings = with.pcg = without.pcg = 0;
  long touching = 0;
  with.driver().contact()->reset_counts();
  for (auto _ : st) {
    const double before = with.ms;
    if (!with.step() || !without.step()) return st.SkipWithError("a simulation step failed");
    st.SetIterationTime((with.ms - before) * 1e-3);
    touching += with.driver().touching_points();
  }
  const double n = static_cast<double>(st.iterations());
  st.counters["contact_ms"] = with.ms / n;
  st.counters["plain_ms"] = without.ms / n;
  st.counters["ratio"] = with.ms / without.ms;
  st.counters["newton_contact"] = static_cast<double>(with.newton) / n;
  st.counters["newton_plain"] = static_cast<double>(without.newton) / n;
  st.counters["pcg_contact"] = static_cast<double>(with.pcg) / n;
  st.counters["pcg_plain"] = static_cast<double>(without.pcg) / n;
  st.counters["halvings_contact"] = static_cast<double>(with.halvings) / n;
  st.counters["touching"] = static_cast<double>(touching) / n;
  st.counters["touching_fraction"] = static_cast<double>(touching) / n / static_cast<double>(m.dense.V.rows());
  st.counters["points"] = static_cast<double>(m.dense.V.rows());
  // the broad phase per evaluation at a new x: its candidates, the points with a term among them
  const mbi::pipeline::SurfaceContact::Counts& c = with.driver().contact()->counts();
  const auto per = [](long long a, long long b) { return b > 0 ? static_cast<double>(a) / static_cast<double>(b) : 0.0; };
  st.counters["candidates"] = per(c.candidates, c.evaluations);
  st.counters["active"] = per(c.active, c.evaluations);
  st.counters["candidates_per_active"] = per(c.candidates, c.active);
  st.counters["move_candidates"] = per(c.move_candidates, c.moves);
  st.counters["substep_points"] = per(c.substep_points, c.substeps);
}

// Not in quick mode (CI): the large scene's contact frames take seconds each.
[[maybe_unused]] const bool registered = [] {
  if (mbi::bench::quick()) return true;
  using mbi::pipeline::Method;
  const auto add = [](const std::string& size, int resolution, Method method, bool blocks_only) {
    benchmark::RegisterBenchmark(("BM_ContactFrame/" + size + "/" + mbi::pipeline::method_name(method) +
                                  (blocks_only ? "-blocks" : "")).c_str(),
                                 BM_ContactFrame, method, blocks_only, resolution)
        ->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(4);
  };
  for (auto [method, blocks_only] : {std::pair(Method::ModifiedBI, false), std::pair(Method::ModifiedBI, true),
                                     std::pair(Method::BI, false)})
    add("large", 205, method, blocks_only);
  // the same scene with the surface resampled: 20,186 and 1,003,688 points
  for (auto [size, resolution] : {std::pair("20K", 58), std::pair("1M", 409)})
    for (Method method : {Method::ModifiedBI, Method::BI}) add(size, resolution, method, false);
  return true;
}();

}  // namespace
