#include "metrics.hpp"

#include <mbi/base/timer.hpp>
#include <mbi/io/atomic_file.hpp>
#include <mbi/scenes/report.hpp>

#include <chrono>
#include <cmath>
#include <string>

namespace mbi::scenes {
namespace {

}  // namespace

RunMetrics::RunMetrics(const Scene& sc, const SceneModels& m, pipeline::FramePipeline& pipe,
                       std::size_t outside_points, const char* renderer, double load_ms, double embed_ms)
    : pipe_(pipe),
      sim_(dynamic_cast<const pipeline::SimulatorDriver*>(&pipe.driver())),
      roundoff_(disc_roundoff(m.U)) {
  const interp::ModifiedBI& solver = pipe.solver();
  json_["scene"] = sc.name;
  json_["scene_file"] = sc.file.string();
  json_["mode"] = mode_name(sc.mode);
  json_["dim"] = m.dim();
  json_["method"] = pipeline::method_name(sc.interpolation.method);
  json_["alpha"] = solver.alpha();
  json_["beta"] = solver.beta();
  json_["pin_boundary"] = sc.interpolation.options.pin_boundary;
  json_["dense_vertices"] = m.dense.V.rows();
  json_["control_vertices"] = m.U.rows();
  json_["elements"] = m.T.rows();
  json_["outside_points"] = outside_points;
  json_["evaluator"] = pipe.evaluator().name();
  json_["renderer"] = renderer;
  json_["timings_ms"] = {{"load", load_ms}, {"generate", m.generate_seconds * 1e3},
                         {"embed", embed_ms}, {"precompute", pipe.precompute_ms()}};
  if (pipe.method() == pipeline::Method::Phong)
    json_["timings_ms"]["phong_precompute"] = pipe.phong_precompute_ms();
  json_["frames"] = nlohmann::json::array();
}

nlohmann::json RunMetrics::start_frame(int f) const {
  nlohmann::json record;
  record["frame"] = f;
  if (sim_) {
    record["time"] = sim_->simulator().time();
    record["newton_iterations"] = f > 0 ? sim_->last_step().newton_iterations : 0;
    record["solver_iterations"] = f > 0 ? sim_->last_step().solver_iterations : 0;
  }
  return record;
}

void RunMetrics::add_timings(nlohmann::json& record, int f) {
  const pipeline::FrameTimings& tm = pipe_.timings();
  record["sim_ms"] = sim_ && f > 0 ? sim_->last_step().total_ms : 0.0;
  record["drive_ms"] = tm.drive_ms;
  record["solve_ms"] = tm.solve_ms + (sim_ ? 0.0 : tm.drive_ms);  // handles: the joint solve
  record["bezier_ms"] = tm.bezier_ms;
  record["interp_ms"] = tm.bezier_ms + tm.evaluate_ms;
  record["upload_ms"] = pipe_.evaluator().timings().upload_ms;
  record["pass_ms"] = pipe_.evaluator().timings().pass_ms;
}

interp::DiscontinuityTable RunMetrics::table() {
  const interp::ModifiedBI& solver = pipe_.solver();
  return pipe_.method() == pipeline::Method::Phong
             ? interp::discontinuity_table(solver, pipe_.control_positions(), pipe_.modified_bi_M(),
                                           pipe_.phong_M())
             : interp::discontinuity_table(solver, pipe_.control_positions(), pipe_.modified_bi_M());
}

interp::DiscontinuityTable RunMetrics::add_discontinuity(nlohmann::json& record) {
  const auto t0 = Clock::now();
  interp::DiscontinuityTable t;
  try {
    t = table();
  } catch (const interp::OverflowError& e) {  // a run error (exit 3), not a library one
    throw SceneError(e.what());
  }
  record["disc"] = disc_json(t, roundoff_);  // throws on a non-finite value
  if (!std::isfinite(t.e_vibr) || !std::isfinite(t.e_disc))
    throw SceneError("E_vibr or E_disc is not finite");
  record["e_vibr"] = t.e_vibr;
  record["e_disc"] = t.e_disc;
  record["metrics_ms"] = ms_since(t0);
  return t;
}

void RunMetrics::finish(const RunResult& res, double pictures_ms) {
  json_["timings_ms"]["pictures"] = pictures_ms;
  json_["frames_completed"] = res.frames;
  json_["failure"] = res.failed ? nlohmann::json(res.message) : nlohmann::json(nullptr);
  const nlohmann::json& frames = json_["frames"];
  const bool has_disc = !frames.empty() && frames.back().contains("disc");
  json_["last_disc"] = has_disc          ? frames.back()["disc"]
                       : frames.empty() ? nlohmann::json(nullptr)
                                        : disc_json(res.last_table, roundoff_);
}

void RunMetrics::write(const std::filesystem::path& dir) const {
  io::write_text_atomic(dir / "metrics.json", json_.dump(1) + "\n");
}

}  // namespace mbi::scenes
