#pragma once
// The GPU evaluator: an OpenGL transform-feedback pass that evaluates every dense point from
// the frame's element Bezier points (docs/method.md facts 5, 6), the same form as the CPU kernel.
//
// Static per-point data is uploaded once (set_points): element id (integer attribute),
// barycentric coordinates, rest position relative to a per-mesh origin, rest normal. Per frame
// only the element Bezier points are uploaded (to a texture buffer, orphaned so that the upload
// never waits for the previous frame's pass). The vertex shader evaluates the displacement from
// the rest pose (B - rest Bezier points) and the analytic normal (cofactor of I + dD/du); transform
// feedback captures both with the rasterizer off, into buffers the renderer draws directly.
// Reading back to the CPU happens only in positions() / normals(): rest position (double) plus
// displacement, so accuracy does not depend on where the model sits in space and the rest pose
// comes back exactly. BI, modified-BI and any other method are the same shader with other points.
//
// All points live in one input and one output buffer per attribute; the pass is split into
// draws of at most `chunk_points` points (binding ranges of the output buffers), so meshes
// beyond one draw's limits (10M points and more) evaluate in several draws.
#include <mbi/gpu/context.hpp>
#include <mbi/pipeline/evaluator.hpp>

namespace mbi::gpu {

struct GpuOptions {
  long long chunk_points = 1 << 22;  ///< points per transform-feedback draw (>= 1)
  /// Wait for the pass to finish and time it (timer query on GPUs; CPU clock around glFinish on
  /// software renderers). Off: evaluate() returns once the commands are queued.
  bool measure = true;
};

class GpuEvaluator final : public pipeline::Evaluator {
 public:
  /// Needs `context` current whenever a member is called. Compiles the shaders for d = 2 and 3
  /// on first use. Throws Error.
  explicit GpuEvaluator(Context& context, const GpuOptions& options = {});
  ~GpuEvaluator() override;
  GpuEvaluator(const GpuEvaluator&) = delete;
  GpuEvaluator& operator=(const GpuEvaluator&) = delete;

  std::string name() const override;
  void set_points(const pipeline::PointSet& points) override;
  void evaluate(const interp::BezierPoints& B, bool normals) override;
  const Eigen::MatrixXd& positions() override;
  const Eigen::MatrixXd& normals() override;
  pipeline::EvaluatorTimings timings() const override { return timings_; }

  // ------------------------------------------------------------------ for renderers and tests
  int dim() const { return dim_; }
  long long points() const { return points_; }
  /// Points written by the last pass (GL_PRIMITIVES_WRITTEN summed over its draws); a capture
  /// that silently wrote nothing shows here.
  long long primitives_written() const { return primitives_; }
  /// Draws of the last pass.
  int draws() const { return draws_; }
  /// The origin subtracted from every position on the GPU (the rest points' bounding-box centre).
  const Eigen::Vector3d& origin() const { return origin_; }
  /// GL buffers (vec3 float per point): rest position - origin; displacement and normal of the
  /// last pass. Draw position = rest + displacement (in the origin's frame).
  unsigned rest_buffer() const { return rest_; }
  unsigned displacement_buffer() const { return out_disp_; }
  unsigned normal_buffer() const { return out_normal_; }
  bool has_normals() const { return have_normals_; }
  /// Fills the output buffers from results evaluated elsewhere (the CPU kernel), p x d each
  /// (normals empty: none), so the renderer draws them as a pass's; after set_points.
  void set_results(const Eigen::MatrixXd& positions, const Eigen::MatrixXd& normals);

 private:
  void release();
  Context& context_;
  GpuOptions options_;
  int dim_ = 0;
  long long points_ = 0, elements_ = 0, primitives_ = 0;
  int draws_ = 0;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  interp::BezierPoints rest_bezier_;
  Eigen::MatrixXd rest_positions_, positions_, normals_;
  bool have_rest_normals_ = false, have_normals_ = false, read_ = false, evaluated_ = false;
  std::vector<float> upload_;  // staging: the frame's displacement control points (vec4 each), or set_results' values
  unsigned program_ = 0, vao_ = 0;
  unsigned element_ = 0, bary_ = 0, rest_ = 0, rest_normal_ = 0;  // static attribute buffers
  unsigned bezier_buffer_ = 0, bezier_texture_ = 0, gradient_buffer_ = 0, gradient_texture_ = 0;
  unsigned out_disp_ = 0, out_normal_ = 0, query_ = 0, timer_ = 0;
  pipeline::EvaluatorTimings timings_;
};

}  // namespace mbi::gpu
