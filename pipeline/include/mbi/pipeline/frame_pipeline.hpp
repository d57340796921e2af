#pragma once
// One frame pipeline for every user of mbi (runner, `mbi deform`, benchmarks, viewer):
//
//   drive the control mesh (Driver) -> solve M (skipped for BI) -> element Bezier points ->
//   evaluate the dense points (Evaluator: CPU or GPU)
//
//   FramePipeline pipe(U, T, interp::embed(U, T, P), std::make_unique<SimulatorDriver>(sim));
//   while (pipe.step().ok) use(pipe.positions());
//
// step() advances one frame (the first call gives frame 0, the initial pose) and records the
// time of each phase. The modified-BI precompute (assembly + factorisation) and Phong's vertex
// weights are computed once, when a method first needs them. Shapes as in mbi::interp: U, X n x d, T m x (d+1), positions p x d.
#include <mbi/interp/phong.hpp>
#include <mbi/pipeline/driver.hpp>
#include <mbi/pipeline/evaluator.hpp>
#include <mbi/pipeline/method.hpp>

#include <memory>
#include <optional>

namespace mbi::pipeline {

struct PipelineOptions {
  Method method = Method::ModifiedBI;
  interp::Options interp;  ///< alpha, beta, pin_boundary, solve path of modified-BI
  bool normals = false;    ///< evaluate normals too (needs rest normals)
};

/// Wall-clock milliseconds of the last frame's phases.
struct FrameTimings {
  double drive_ms = 0;     ///< simulator step, handle solve, or copying given positions
  double solve_ms = 0;     ///< M from X (0 for BI, and when the driver solved M; Phong: closed form)
  double bezier_ms = 0;    ///< element control points
  double evaluate_ms = 0;  ///< dense points (the evaluator's pass)
  double total_ms() const { return drive_ms + solve_ms + bezier_ms + evaluate_ms; }
};

struct FrameResult {
  bool ok = true;
  std::string message;  ///< why the frame failed (the driver's message)
  int frame = -1;       ///< the frame computed (the last good one on failure)
};

class FramePipeline {
 public:
  /// U n x d, T m x (d+1): the control mesh; embedding: the dense points in it (interp::embed).
  /// evaluator: nullptr = CpuEvaluator(double). rest_normals: p x d unit normals, needed when
  /// options.normals is set. Throws mbi::Error on inconsistent sizes.
  FramePipeline(const Eigen::Ref<const Eigen::MatrixXd>& U,
                const Eigen::Ref<const Eigen::MatrixXi>& T, interp::Embedding embedding,
                std::unique_ptr<Driver> driver, const PipelineOptions& options = {},
                std::unique_ptr<Evaluator> evaluator = nullptr,
                const Eigen::MatrixXd& rest_normals = Eigen::MatrixXd());
  ~FramePipeline();
  FramePipeline(FramePipeline&&) noexcept;
  FramePipeline& operator=(FramePipeline&&) noexcept;

  /// Computes the next frame. With evaluate = false the dense points are left for a later
  /// evaluate() (a frame that is only written now and then). On a driver failure the results
  /// stay those of the last good frame.
  FrameResult step(bool evaluate = true);
  /// Evaluates the dense points of the current frame (if step() skipped it).
  void evaluate();
  /// The driver's initial pose comes next; frame() is -1 again.
  void reset();
  int frame() const;  ///< last completed frame, -1 before the first step

  // --------------------------------------------------------------- results of the current frame
  const Eigen::MatrixXd& control_positions() const;  ///< X, n x d
  const interp::VertexMatrices& M() const;          ///< the method's M ((n d) x d; 0 for BI)
  const interp::BezierPoints& bezier() const;
  const Eigen::MatrixXd& positions();  ///< p x d (from the evaluator)
  const Eigen::MatrixXd& normals();    ///< p x d (options.normals)
  const FrameTimings& timings() const;

  /// Modified-BI's M at the current X, whatever the method (solved on demand for BI): for the
  /// discontinuity table and side-by-side comparisons.
  const interp::VertexMatrices& modified_bi_M();
  /// Phong's M at the current X, whatever the method (computed on demand, cached per frame).
  const interp::VertexMatrices& phong_M();
  /// The current frame's dense positions with another method (CPU, double): comparison
  /// pictures and metrics. For the pipeline's own method it returns positions().
  void evaluate_with(Method method, Eigen::MatrixXd& out);
  /// The current frame's Bezier points with another method (for evaluating it elsewhere, e.g.
  /// a picture's second panel on the GPU).
  interp::BezierPoints bezier_with(Method method);

  // --------------------------------------------------------------- settings
  Method method() const;
  /// Takes effect from the next step() (or evaluate()).
  void set_method(Method method);
  /// Changes alpha (> 0): refactors modified-BI (if it was precomputed).
  void set_alpha(double alpha);
  const PipelineOptions& options() const;

  // --------------------------------------------------------------- parts
  /// Modified-BI precompute (built on first use). Throws as interp::ModifiedBI does.
  const interp::ModifiedBI& solver();
  /// Phong's vertex weights (built on first use). Throws as interp::Phong does.
  const interp::Phong& phong();
  /// Milliseconds the modified-BI precompute took (0 until it ran).
  double precompute_ms() const;
  /// Milliseconds Phong's weights took (0 until computed).
  double phong_precompute_ms() const;
  Driver& driver();
  /// Replaces the driver (e.g. the viewer switching between simulation and direct handles) and
  /// returns the old one; frames go on from the current frame number, the next step() asks the
  /// new driver.
  std::unique_ptr<Driver> set_driver(std::unique_ptr<Driver> driver);
  Evaluator& evaluator();
  const interp::Embedding& embedding() const;
  const Eigen::MatrixXd& rest_positions() const;
  const Eigen::MatrixXi& elements() const;
  int dim() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mbi::pipeline
