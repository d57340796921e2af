#include "evaluation.hpp"

#include <mbi/base/timer.hpp>

#include <array>

namespace mbi::viewer {

EvaluatorChoice choose_evaluator(scenes::GpuUse use, const std::string& gl_renderer) {
  if (use == scenes::GpuUse::Off) return {scenes::GpuUse::Off, "--gpu off"};
  if (use == scenes::GpuUse::On) return {scenes::GpuUse::On, "--gpu on"};
  for (const char* software : std::array{"llvmpipe", "softpipe", "SwiftShader"})
    if (gl_renderer.find(software) != std::string::npos)
      return {scenes::GpuUse::Off, std::string("software OpenGL (") + software + "): the CPU kernel is faster"};
  return {scenes::GpuUse::On, "hardware OpenGL"};
}

DrawnEvaluator::DrawnEvaluator(std::unique_ptr<pipeline::Evaluator> cpu, std::unique_ptr<gpu::GpuEvaluator> buffers)
    : cpu_(std::move(cpu)), buffers_(std::move(buffers)) {}

void DrawnEvaluator::set_points(const pipeline::PointSet& points) {
  cpu_->set_points(points);
  buffers_->set_points(points);
}

void DrawnEvaluator::evaluate(const interp::BezierPoints& B, bool normals) {
  cpu_->evaluate(B, normals);
  const auto started = Clock::now();
  static const Eigen::MatrixXd none;
  buffers_->set_results(cpu_->positions(), normals ? cpu_->normals() : none);
  timings_ = cpu_->timings();
  timings_.upload_ms += ms_since(started);
}

}  // namespace mbi::viewer
