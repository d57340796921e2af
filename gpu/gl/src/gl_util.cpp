#include "gl_util.hpp"

#include <cstdio>

namespace mbi::gpu::detail {
namespace {

GLuint shader(GLenum type, const std::string& source) {
  const GLuint s = glCreateShader(type);
  const char* src = source.c_str();
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw Error(std::string("OpenGL: shader does not compile: ") + log);
  }
  return s;
}

}  // namespace

GLuint program(const std::string& defines, const char* vs, const char* fs,
               const std::vector<const char*>& feedback) {
  const std::string head = "#version 330 core\n" + defines;
  const GLuint p = glCreateProgram();
  const GLuint v = shader(GL_VERTEX_SHADER, head + vs);
  glAttachShader(p, v);
  GLuint f = 0;
  if (fs) {
    f = shader(GL_FRAGMENT_SHADER, head + fs);
    glAttachShader(p, f);
  }
  if (!feedback.empty())
    glTransformFeedbackVaryings(p, static_cast<GLsizei>(feedback.size()), feedback.data(),
                                GL_SEPARATE_ATTRIBS);
  glLinkProgram(p);
  glDeleteShader(v);
  if (f) glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    glDeleteProgram(p);
    throw Error(std::string("OpenGL: program does not link: ") + log);
  }
  return p;
}

void check(const char* what) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", e);
    throw Error(std::string("OpenGL error ") + code + " in " + what);
  }
}

}  // namespace mbi::gpu::detail
