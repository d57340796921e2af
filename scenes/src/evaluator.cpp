#include <mbi/gpu/context.hpp>
#include <mbi/gpu/evaluator.hpp>
#include <mbi/scenes/evaluator.hpp>

namespace mbi::scenes {

Evaluation make_evaluator(GpuUse use, const std::function<void(const std::string&)>& warn,
                          std::shared_ptr<gpu::Context> context, pipeline::Precision cpu) {
  Evaluation e;
  if (use != GpuUse::Off && context) {
    e.context = std::move(context);
  } else if (use != GpuUse::Off) {
    try {
      e.context = gpu::Context::headless();
    } catch (const gpu::Error& err) {
      if (use == GpuUse::On) throw Error(std::string("gpu = ") + gpu_name(use) + ", but " + err.what());
      warn(std::string("note: ") + err.what() + "; evaluating and drawing on the CPU");
    }
  }
  if (e.context)
    e.evaluator = std::make_unique<gpu::GpuEvaluator>(*e.context);
  else
    e.evaluator = std::make_unique<pipeline::CpuEvaluator>(cpu);
  return e;
}

}  // namespace mbi::scenes
