#pragma once
// metrics.json of a run: what ran (scene, mode, method, alpha and beta, sizes, evaluator and
// renderer), the setup's timings, one record a frame (the phases' timings, the simulator's
// iterations, the discontinuity table) and how the run ended.
#include <mbi/interp/metrics.hpp>
#include <mbi/pipeline/driver.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/scenes/runner.hpp>

#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>

namespace mbi::scenes {

class RunMetrics {
 public:
  /// The run's header. Builds the pipeline's modified-BI solver (alpha, beta, the energies of
  /// the discontinuity table).
  RunMetrics(const Scene& sc, const SceneModels& m, pipeline::FramePipeline& pipe,
             std::size_t outside_points, const char* renderer, double load_ms, double embed_ms);

  /// The record of the frame the pipeline just stepped: its number and, in a simulation, the
  /// simulated time and the iterations.
  nlohmann::json start_frame(int f) const;
  /// The frame's timings (ms) into its record.
  void add_timings(nlohmann::json& record, int f);
  /// The discontinuity table at the frame's control positions (BI against modified-BI, and
  /// Phong in a Phong run) into its record; throws SceneError when a value is not finite.
  interp::DiscontinuityTable add_discontinuity(nlohmann::json& record);
  void add_frame(nlohmann::json record) { json_["frames"].push_back(std::move(record)); }

  /// The discontinuity table of the pipeline's current frame.
  interp::DiscontinuityTable table();
  /// Round-off level of the discontinuities (report.hpp disc_roundoff).
  double roundoff() const { return roundoff_; }

  /// How the run ended: frames completed, the failure, the table of the last good frame (from
  /// its record, or res.last_table), the time drawing the pictures took.
  void finish(const RunResult& res, double pictures_ms);
  /// Writes metrics.json into `dir` (atomically).
  void write(const std::filesystem::path& dir) const;

 private:
  pipeline::FramePipeline& pipe_;
  const pipeline::SimulatorDriver* sim_;  // null in a drag scene
  double roundoff_;
  nlohmann::json json_;
};

}  // namespace mbi::scenes
