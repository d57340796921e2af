#pragma once
// What evaluates the dense points of a run (GpuUse): the GPU (OpenGL transform feedback on a
// headless EGL context) or the CPU. No GL header here: mbi::gpu is a private
// dependency of mbi::scenes, and its context is only named.
#include <mbi/pipeline/evaluator.hpp>
#include <mbi/scenes/scene.hpp>

#include <functional>
#include <memory>
#include <string>

namespace mbi::gpu {
class Context;
}  // namespace mbi::gpu

namespace mbi::scenes {

struct Evaluation {
  /// The headless OpenGL context of a GPU evaluator, null for the CPU. Keep it while the
  /// evaluator (or the pipeline it was moved into) lives; 3D pictures are drawn on it too.
  std::shared_ptr<gpu::Context> context;
  /// gpu::GpuEvaluator on `context`, or pipeline::CpuEvaluator.
  std::unique_ptr<pipeline::Evaluator> evaluator;
};

/// The evaluator `use` asks for. Off: the CPU. On: the GPU, or Error "gpu = on, but <why
/// no OpenGL context>". Auto: the GPU when a headless OpenGL context can be made, else the CPU,
/// after warn("note: <why>; evaluating and drawing on the CPU"). With `context` (a window's, the
/// viewer's), On and Auto evaluate in it instead of a headless one. `cpu`: the CPU evaluator's
/// precision (double for written outputs; the viewer draws float, FastEvaluator's kernels).
Evaluation make_evaluator(GpuUse use, const std::function<void(const std::string&)>& warn,
                          std::shared_ptr<gpu::Context> context = nullptr,
                          pipeline::Precision cpu = pipeline::Precision::Double);

}  // namespace mbi::scenes
