#pragma once
// metrics.json of a run: what ran (scene, mode, method, alpha and beta, sizes, evaluator and
// renderer), the setup's timings, one record a frame (the phases' timings, the simulator's
// iterations, the discontinuity table) and how the run ended.
#include <mbi/interp/metrics.hpp>
#include <mbi/pipeline/driver.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/scenes/runner.hpp>

#include <nlohmann/json.hpp>

#include <mbi/io/scratch_file.hpp>

#include <cstddef>
#include <filesystem>
#include <memory>

namespace mbi::scenes {

class RunMetrics {
 public:
  /// The run's header. Builds the pipeline's modified-BI solver (alpha, beta, the energies of
  /// the discontinuity table). `dir`: the output folder, where the frames' records wait.
  RunMetrics(const Scene& sc, const SceneModels& m, pipeline::FramePipeline& pipe,
             std::size_t outside_points, const char* renderer, double load_ms, double embed_ms,
             const std::filesystem::path& dir);

  /// The record of the frame the pipeline just stepped: its number and, in a simulation, the
  /// simulated time and the iterations.
  nlohmann::json start_frame(int f) const;
  /// The frame's timings (ms) into its record.
  void add_timings(nlohmann::json& record, int f);
  /// The discontinuity table at the frame's control positions (BI against modified-BI, and
  /// Phong in a Phong run) into its record; throws Error when a value is not finite.
  interp::DiscontinuityTable add_discontinuity(nlohmann::json& record);
  /// Adds the frame's record, with the process's resident memory now (rss_kb). When metrics.json
  /// is written, records wait in a scratch file in the output folder (memory stays bounded over
  /// any number of frames); added whole or not at all (throws io::Error on a full disk).
  void add_frame(nlohmann::json record);
  /// Forgets the record add_frame() added last (a later part of that frame failed).
  void discard_last();

  /// The discontinuity table of the pipeline's current frame.
  interp::DiscontinuityTable table();
  /// Round-off level of the discontinuities (report.hpp disc_roundoff).
  double roundoff() const { return roundoff_; }

  /// How the run ended: frames completed, the failure or interruption, the table of the last
  /// good frame (from its record, or res.last_table), the time drawing the pictures took.
  void finish(const RunResult& res, double pictures_ms);
  /// Writes metrics.json into the output folder (atomically).
  void write() const;

 private:
  pipeline::FramePipeline& pipe_;
  const pipeline::SimulatorDriver* sim_;  // null in a drag scene
  double roundoff_;
  nlohmann::json json_;  // everything but the frames' records
  std::filesystem::path dir_;
  bool keep_records_;                          // metrics.json is written
  std::unique_ptr<io::ScratchFile> records_;   // the records, as written in metrics.json
  nlohmann::json last_, before_last_;          // the last record, and the one before it
  long frames_ = 0, last_at_ = 0;              // records added; where the last one starts
};

/// The resident memory of this process in kB (Linux /proc/self/statm), or -1 when unknown.
long resident_kb();

}  // namespace mbi::scenes
