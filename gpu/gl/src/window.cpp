#include <mbi/gpu/window.hpp>

#include <mbi/gpu/renderer.hpp>

#include "gl_util.hpp"

#include <string>

namespace mbi::gpu {
namespace {

void check_size(const char* what, int width, int height) {
  if (width < 0 || height < 0)
    throw Error(std::string(what) + ": negative size " + std::to_string(width) + " x " + std::to_string(height));
}

}  // namespace

void clear_window(int width, int height, const Eigen::Vector3d& rgb) {
  check_size("clear_window", width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, width, height);
  glClearColor(static_cast<float>(rgb.x()), static_cast<float>(rgb.y()), static_cast<float>(rgb.z()), 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

void viewport(int x, int y, int width, int height) {
  check_size("viewport", width, height);
  glViewport(x, y, width, height);
}

void finish() { glFinish(); }

io::Image read_window(int width, int height) {
  glReadBuffer(GL_BACK);
  return read_picture(width, height);
}

}  // namespace mbi::gpu
