#include "gl_program.hpp"

#include <mbi/viewer/error.hpp>

#include <string>

namespace mbi::viewer {
namespace {

GLuint shader(const char* what, GLenum kind, const char* source) {
  const GLuint s = glCreateShader(kind);
  const char* parts[2] = {"#version 330 core\n", source};
  glShaderSource(s, 2, parts, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw Error(std::string(what) + ": shader: " + log);
  }
  return s;
}

}  // namespace

GLuint link_program(const char* what, const char* vertex, const char* fragment) {
  const GLuint vs = shader(what, GL_VERTEX_SHADER, vertex);
  GLuint fs = 0;
  try {
    fs = shader(what, GL_FRAGMENT_SHADER, fragment);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    glDeleteProgram(p);
    throw Error(std::string(what) + ": shader: " + log);
  }
  return p;
}

}  // namespace mbi::viewer
