#pragma once
// Which evaluator the viewer runs (internal), and the CPU kernel drawn through the same GL
// buffers as the GPU pass, so the renderer draws either without knowing which ran.
#include <mbi/gpu/evaluator.hpp>
#include <mbi/scenes/scene.hpp>

#include <memory>
#include <string>

namespace mbi::viewer {

/// The evaluator --gpu asks for, decided: On (the GPU) or Off (the CPU), and why (the HUD).
struct EvaluatorChoice {
  scenes::GpuUse use = scenes::GpuUse::On;
  std::string why;
};

/// Auto: the CPU on a software OpenGL renderer (llvmpipe, softpipe, SwiftShader: it runs the GPU
/// pass on the same cores, far slower than the CPU kernel), else the GPU.
EvaluatorChoice choose_evaluator(scenes::GpuUse use, const std::string& gl_renderer);

/// A CPU evaluator whose results are uploaded into a GpuEvaluator's output buffers after each
/// evaluate(); the upload is counted as its upload time.
class DrawnEvaluator final : public pipeline::Evaluator {
 public:
  DrawnEvaluator(std::unique_ptr<pipeline::Evaluator> cpu, std::unique_ptr<gpu::GpuEvaluator> buffers);
  std::string name() const override { return cpu_->name(); }
  void set_points(const pipeline::PointSet& points) override;
  void evaluate(const interp::BezierPoints& B, bool normals) override;
  const Eigen::MatrixXd& positions() override { return cpu_->positions(); }
  const Eigen::MatrixXd& normals() override { return cpu_->normals(); }
  pipeline::EvaluatorTimings timings() const override { return timings_; }
  gpu::GpuEvaluator& buffers() { return *buffers_; }

 private:
  std::unique_ptr<pipeline::Evaluator> cpu_;
  std::unique_ptr<gpu::GpuEvaluator> buffers_;
  pipeline::EvaluatorTimings timings_;
};

}  // namespace mbi::viewer
