#include <mbi/gpu/program.hpp>

#include "shader_files.hpp"  // generated from gpu/gl/shaders/ (CMakeLists.txt)

#include <epoxy/gl.h>

namespace mbi::gpu {

namespace shaders {
const ShaderSource mesh{mesh_vert, mesh_frag};
const ShaderSource texture{texture_vert, texture_frag};
const ShaderSource line{line_vert, line_frag};
const ShaderSource material{material_vert, material_frag};
const ShaderSource ground{ground_vert, ground_frag};
}  // namespace shaders

namespace {

// The driver's log of a shader or program that failed, as an Error.
[[noreturn]] void fail(const char* what, const char* problem, const char* log) {
  throw Error(std::string("OpenGL: ") + what + ": " + problem + ": " + log);
}

GLuint shader(const char* what, GLenum type, const std::string& source) {
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
    fail(what, "shader does not compile", log);
  }
  return s;
}

}  // namespace

unsigned program(const char* what, const ShaderSource& source, const std::string& defines,
                 const std::vector<const char*>& feedback) {
  if (!source.vertex) throw Error(std::string("OpenGL: ") + what + ": no vertex shader");
  const std::string head = "#version 330 core\n" + defines;
  const GLuint v = shader(what, GL_VERTEX_SHADER, head + source.vertex);
  GLuint f = 0;
  try {
    if (source.fragment) f = shader(what, GL_FRAGMENT_SHADER, head + source.fragment);
  } catch (...) {
    glDeleteShader(v);
    throw;
  }
  const GLuint p = glCreateProgram();
  glAttachShader(p, v);
  if (f) glAttachShader(p, f);
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
    fail(what, "program does not link", log);
  }
  return p;
}

}  // namespace mbi::gpu
