#pragma once
// mbi deform's outputs, one a dense part: a plain file of the one pose (surface, points or a
// static glTF, written atomically at the end), a point cache (.pc2, .mdd), an animated glTF, or
// numbered files (one a frame, each complete when it appears). Every output is checked before
// any work; frames are written as they come.
#include "deform_inputs.hpp"

#include <mbi/interp/fast_evaluate.hpp>
#include <mbi/io/atomic_file.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mbi::cli {

enum class OutKind { file, pc2, mdd, gltf, numbered };

/// One --out: its name, kind and index in the command's OutputSet (all but numbered files).
struct Out {
  std::string name;
  OutKind kind = OutKind::file;
  std::size_t index = 0;
};

/// The kind of each --out: a plain file for one pose, else by its name (throws for a name that
/// holds no sequence).
std::vector<Out> output_kinds(const std::vector<std::string>& outs, bool trajectory);
/// Reserves each output in `outputs` (the overwrite rule) and checks a plain file's format.
void reserve_outputs(std::vector<Out>& outs, io::OutputSet& outputs);
/// Every output, numbered files expanded, checked together: each follows the overwrite rule on
/// its own, and no two (two series, a series and a cache, glTF or --stats) name one file.
void check_outputs(const std::vector<Out>& outs, const std::string& stats, const std::vector<std::filesystem::path>& inputs,
                   bool force, int frames);

/// The output's timing: PC2 start frame and sample rate (frames), MDD and glTF times (s).
struct Timing {
  float pc2_start = 0.0f, pc2_rate = 1.0f;
  std::vector<float> mdd_times;
  std::vector<double> gltf_times;  ///< strictly increasing, as glTF keys must be
};
/// Frames per second where times meet frame numbers when --fps is not given.
constexpr double kDefaultFps = 24;

/// The timing of `frames` (none for one pose); per-frame times only when an output needs them
/// (MDD, glTF). Resampled frames (`fps` given): PC2 start t0 * fps and rate 1, their times.
Timing output_timing(Frames& frames, std::optional<double> fps, const std::vector<Out>& outs);

/// --fps's text as a number: decimal, finite and > 0, or an error saying so.
double parse_fps(const std::string& text);
/// An --fps whose frame times k / fps (s) are finite and strictly increasing as float32 for every
/// frame; `frames` at least 1.
void check_fps(double fps, int frames);

class PartWriter;

/// Every --out, one a dense part, fed the rows of its part.
class FrameWriter {
 public:
  FrameWriter(const std::vector<Out>& outs, const io::OutputSet& outputs, const Model& m, const Timing& timing);
  ~FrameWriter();
  /// positions p x d (double), normals p x 3 or empty
  void write(int k, const Eigen::MatrixXd& positions, const Eigen::MatrixXd& normals);
  /// positions p x 3 floats, row-major (caches only)
  void write(const interp::RowMatrixXf& xyz);
  /// Completes every output (a cache's header, a glTF, a plain file into its staging name).
  void finish();

 private:
  const Model& model_;
  std::vector<std::unique_ptr<PartWriter>> parts_;
};

}  // namespace mbi::cli
