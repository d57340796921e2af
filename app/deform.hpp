#pragma once
// mbi deform: one path for one pose and for a whole animation. One pose is a trajectory of one
// frame: the models are loaded, the points embedded and the method precomputed once
// (pipeline::Deformer), then every frame is read, deformed and written as it comes, so memory
// holds a frame or two whatever the length; the last frame is compared across BI, Phong and
// modified-BI for the summary and --stats. See docs/cli.md.
#include "deform_inputs.hpp"

#include <mbi/interp/memory.hpp>
#include <mbi/interp/metrics.hpp>
#include <mbi/pipeline/deformer.hpp>

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mbi::cli {

struct DeformArgs {
  std::string control, deformed, stats, example;
  std::string displacement;  ///< a point field of the --deformed files added to their positions; empty: none
  std::vector<std::string> meshes, outs;  ///< one --out for each --mesh
  pipeline::Method method = pipeline::Method::ModifiedBI;
  std::optional<double> alpha;  ///< none: interp's default
  bool pin_boundary = false, force = false;
  std::optional<double> max_outside;  ///< refuse points farther out (x the model size)
  double max_memory = 0;  ///< bytes the run may take (--max-memory); 0: MemAvailable
  /// The output's frame rate: the frames resampled to it (Frames::resample); none: the input's
  /// frames as they are, at kDefaultFps where times meet frame numbers.
  std::optional<double> fps;
};

/// Runs it; returns the exit code: 0, 3 when a frame failed after earlier ones were written (they
/// are kept), 128 + the signal when SIGINT or SIGTERM stopped it. Throws (exit 2, nothing
/// written) on bad input found before the first frame is written.
int run_deform(const DeformArgs& a);

/// How the frames went.
struct Run {
  int done = 0, frames = 0, signal = 0;
  bool trajectory = false;  ///< frames from a trajectory (else one pose)
  std::string failure;
  Eigen::MatrixXd last_pose;  ///< the control positions of the last frame done
  double embed_ms = 0, precompute_ms = 0, phong_ms = 0, read_ms = 0, deform_ms = 0, write_ms = 0;
  double estimate_ms = 0, solve_ms = 0;  ///< the memory estimate; one modified-BI solve (the comparison's)
  interp::MemoryEstimate estimate;       ///< the run's memory estimate (scenes::check_run_size)
};

/// BI, Phong and modified-BI side by side at the last frame.
struct Comparison {
  bool built = false;  ///< false: no interior face (one element), modified-BI is not built
  double alpha = 0, beta = 0;
  int null_space_dim = 0;
  std::string factorization;  ///< of the modified-BI solver, with its factor's size and kept bytes
  long long factor_nonzeros = 0, factor_stored_values = 0, factor_index_bytes = 0, kept_bytes = 0;
  bool dense_operator = false;
  interp::DiscontinuityTable table;
  /// Against the closed-form deformation (the example): BI, Phong, modified-BI.
  std::vector<std::pair<std::string, interp::Accuracy>> accuracy;
};

/// The comparison at run.last_pose; builds what the deformer's method did not (timed into run).
Comparison compare_methods(const Model& m, const pipeline::Deformer& deformer, Run& run);
nlohmann::json stats_json(const DeformArgs& a, const Model& m, const pipeline::Deformer& deformer, const Run& run,
                          const std::optional<Comparison>& c);
void print_summary(const DeformArgs& a, const Model& m, const pipeline::Deformer& deformer, const Run& run,
                   const std::optional<Comparison>& c);

}  // namespace mbi::cli
