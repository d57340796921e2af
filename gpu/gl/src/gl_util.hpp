#pragma once
// Small OpenGL helpers of mbi::gpu (shader programs, error checks).
#include <mbi/gpu/context.hpp>

#include <epoxy/gl.h>

#include <string>
#include <vector>

namespace mbi::gpu::detail {

/// Compiles and links a program from "#version 330 core" + `defines` + each source. Transform
/// feedback varyings (if any) are set before linking. Throws Error with the driver's log.
GLuint program(const std::string& defines, const char* vs, const char* fs,
               const std::vector<const char*>& feedback = {});

/// Throws Error naming `what` if glGetError reports an error.
void check(const char* what);

}  // namespace mbi::gpu::detail
