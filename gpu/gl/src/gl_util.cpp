#include "gl_util.hpp"

#include <cstdio>
#include <string>

namespace mbi::gpu::detail {

void check(const char* what) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", e);
    throw Error(std::string("OpenGL error ") + code + " in " + what);
  }
}

}  // namespace mbi::gpu::detail
