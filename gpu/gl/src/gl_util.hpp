#pragma once
// Small OpenGL helpers of mbi::gpu (error checks).
#include <mbi/gpu/context.hpp>

#include <epoxy/gl.h>

namespace mbi::gpu::detail {

/// Throws Error naming `what` if glGetError reports an error.
void check(const char* what);

}  // namespace mbi::gpu::detail
