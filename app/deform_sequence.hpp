#pragma once
// mbi deform on a whole animation: one embedding and one precompute (pipeline::Deformer), then
// every frame of a control trajectory read, deformed and written as it comes, so that memory
// holds a frame or two whatever the length. See docs/cli.md, "Sequences".
#include <mbi/pipeline/method.hpp>

#include <optional>
#include <string>
#include <vector>

namespace mbi::cli {

struct SequenceArgs {
  std::string control, deformed;
  std::vector<std::string> meshes, outs;  ///< one --out for each dense model
  std::string stats;
  pipeline::Method method = pipeline::Method::ModifiedBI;
  std::optional<double> alpha;        ///< none: the method's default
  bool pin_boundary = false, force = false;
  std::optional<double> max_outside;  ///< refuse points farther out (x the model size)
  double fps = 24;                    ///< frames per second, where times and frames meet
};

/// Whether the arguments ask for a sequence: `deformed` names a trajectory (io::Trajectory) or
/// an output is a point cache (.pc2, .mdd) or numbered files (a printf pattern).
bool is_sequence(const std::string& deformed, const std::vector<std::string>& outs);

/// Runs it; returns the exit code: 0, 3 when a frame failed after earlier ones were written (they
/// are kept), 128 + the signal when SIGINT or SIGTERM stopped it. Throws (exit 2, nothing
/// written) on bad input found before the first frame is written.
int run_deform_sequence(const SequenceArgs& a);

/// --fps's text as a number: decimal, finite and > 0, or an error saying so (whether its frame
/// times fit float32 is checked against the trajectory's length when it is opened).
double parse_fps(const std::string& text);

}  // namespace mbi::cli
