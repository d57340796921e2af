#pragma once
// OpenGL contexts for mbi::gpu. Headless: EGL without any window or display (Mesa's surfaceless
// platform, e.g. llvmpipe in CI, or an EGL device such as an NVIDIA GPU), OpenGL 3.3+ core. In a
// window (the viewer): adopt the context GLFW made current. All GL entry points go through one
// loader, libepoxy, for EGL and GLX contexts alike.
#include <mbi/error.hpp>

#include <memory>
#include <string>

namespace mbi::gpu {

/// No usable OpenGL (no driver, no display, too old a version, a shader that does not compile).
class Error : public mbi::Error {
 public:
  using mbi::Error::Error;
};

class Context {
 public:
  /// A headless context, made current on this thread. Tries EGL's surfaceless platform, then
  /// each EGL device, then the default display. Throws Error saying why none is usable. The
  /// environment variable MBI_GL=none makes it fail on purpose (tests, forcing the CPU path).
  static std::unique_ptr<Context> headless();
  /// The context current on this thread (made by GLFW or another toolkit); not owned.
  static std::unique_ptr<Context> adopt_current();
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  /// Makes this context current on the calling thread (headless contexts only; a no-op else).
  void make_current();
  const std::string& renderer() const { return renderer_; }  ///< GL_RENDERER
  const std::string& version() const { return version_; }    ///< GL_VERSION
  /// True for CPU implementations (llvmpipe, softpipe, swrast): their timer queries miss the
  /// vertex stage, so passes are timed with a CPU clock around glFinish.
  bool software() const { return software_; }
  /// A complete 1 x 1 framebuffer: bound for transform-feedback passes, because a surfaceless
  /// context has no default framebuffer and draws would fail silently without one.
  unsigned dummy_framebuffer() const { return fbo_; }

 private:
  Context() = default;
  void init_gl();
  struct Egl;
  std::unique_ptr<Egl> egl_;
  std::string renderer_, version_;
  bool software_ = false;
  unsigned fbo_ = 0, rbo_ = 0;
};

/// GL_RENDERER of the context current on this thread (a window's, before any Context adopts
/// it); empty where the driver gives none.
std::string renderer_name();

}  // namespace mbi::gpu
