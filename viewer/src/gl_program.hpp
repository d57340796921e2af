#pragma once
// Shader programs of the viewer's own drawing (internal): compiled from GLSL 3.30 sources.
#include <epoxy/gl.h>

namespace mbi::viewer {

/// Links a program from a vertex and a fragment shader ("#version 330 core" prepended). Throws
/// Error "<what>: shader: <log>" when one does not compile or link.
GLuint link_program(const char* what, const char* vertex, const char* fragment);

}  // namespace mbi::viewer
