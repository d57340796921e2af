#include <mbi/gpu/context.hpp>

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <cstdlib>
#include <cstring>
#include <vector>

namespace mbi::gpu {

struct Context::Egl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
};

namespace {

// A core context of version 4.5 down to 3.3 on an initialised display; EGL_NO_CONTEXT if none.
EGLContext core_context(EGLDisplay dpy, std::string& why) {
  if (!eglBindAPI(EGL_OPENGL_API)) {
    why = "EGL has no desktop OpenGL API";
    return EGL_NO_CONTEXT;
  }
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint n = 0;
  const bool have_config = eglChooseConfig(dpy, config_attribs, &config, 1, &n) && n > 0;
  const int versions[][2] = {{4, 6}, {4, 5}, {4, 3}, {4, 1}, {3, 3}};
  for (const auto& v : versions) {
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, v[0], EGL_CONTEXT_MINOR_VERSION, v[1],
                              EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_NONE};
    const EGLContext ctx =
        eglCreateContext(dpy, have_config ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
    if (ctx != EGL_NO_CONTEXT) return ctx;
  }
  why = "no OpenGL 3.3+ core context";
  return EGL_NO_CONTEXT;
}

bool try_display(EGLDisplay dpy, Context* /*unused*/, EGLDisplay& out_dpy, EGLContext& out_ctx,
                 std::string& why) {
  if (dpy == EGL_NO_DISPLAY) return false;
  EGLint major = 0, minor = 0;
  if (!eglInitialize(dpy, &major, &minor)) {
    why = "eglInitialize failed";
    return false;
  }
  const EGLContext ctx = core_context(dpy, why);
  if (ctx == EGL_NO_CONTEXT) {
    eglTerminate(dpy);
    return false;
  }
  if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    why = "eglMakeCurrent without a surface failed";
    eglDestroyContext(dpy, ctx);
    eglTerminate(dpy);
    return false;
  }
  out_dpy = dpy;
  out_ctx = ctx;
  return true;
}

}  // namespace

std::unique_ptr<Context> Context::headless() {
  if (const char* v = std::getenv("MBI_GL"); v && std::strcmp(v, "none") == 0)
    throw Error("no OpenGL context: disabled by the environment (MBI_GL=none)");
  std::unique_ptr<Context> c(new Context);
  c->egl_ = std::make_unique<Egl>();
  std::string why = "EGL is not available";
  EGLDisplay dpy = EGL_NO_DISPLAY;
  EGLContext ctx = EGL_NO_CONTEXT;
  bool ok = false;
  const bool has_platform = epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_base");
  if (has_platform && epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless"))
    ok = try_display(eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
                     c.get(), dpy, ctx, why);
  if (!ok && has_platform && epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_device_enumeration")) {
    EGLint n = 0;
    eglQueryDevicesEXT(0, nullptr, &n);
    std::vector<EGLDeviceEXT> devices(static_cast<size_t>(std::max(n, 0)));
    if (n > 0 && eglQueryDevicesEXT(n, devices.data(), &n))
      for (EGLint i = 0; i < n && !ok; ++i)
        ok = try_display(eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[static_cast<size_t>(i)], nullptr),
                         c.get(), dpy, ctx, why);
  }
  if (!ok) ok = try_display(eglGetDisplay(EGL_DEFAULT_DISPLAY), c.get(), dpy, ctx, why);
  if (!ok) throw Error("no OpenGL context: " + why);
  c->egl_->display = dpy;
  c->egl_->context = ctx;
  c->init_gl();
  return c;
}

std::unique_ptr<Context> Context::adopt_current() {
  std::unique_ptr<Context> c(new Context);
  c->init_gl();
  return c;
}

void Context::init_gl() {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  if (!r || !v) throw Error("no OpenGL context is current");
  renderer_ = r;
  version_ = v;
  if (epoxy_gl_version() < 33) throw Error("OpenGL " + version_ + " is older than 3.3");
  software_ = renderer_.find("llvmpipe") != std::string::npos ||
              renderer_.find("softpipe") != std::string::npos ||
              renderer_.find("swrast") != std::string::npos;
  glGenRenderbuffers(1, &rbo_);
  glBindRenderbuffer(GL_RENDERBUFFER, rbo_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, 1, 1);
  glGenFramebuffers(1, &fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rbo_);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw Error("OpenGL: cannot make a complete framebuffer (" + renderer_ + ")");
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

Context::~Context() {
  if (egl_ && egl_->context != EGL_NO_CONTEXT) {
    eglMakeCurrent(egl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, egl_->context);
    if (fbo_) glDeleteFramebuffers(1, &fbo_);
    if (rbo_) glDeleteRenderbuffers(1, &rbo_);
    eglMakeCurrent(egl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(egl_->display, egl_->context);
    eglTerminate(egl_->display);
  }
}

void Context::make_current() {
  if (egl_ && egl_->context != EGL_NO_CONTEXT)
    eglMakeCurrent(egl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, egl_->context);
}

std::string renderer_name() {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return r ? r : "";
}

}  // namespace mbi::gpu
