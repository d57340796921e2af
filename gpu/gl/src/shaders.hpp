#pragma once
// The evaluation pass's vertex shader (GLSL 3.30 core: transform feedback, integer attributes
// and texture buffers, no compute shaders). "#version" and "#define D <dim>" are prepended.
#include "shader_files.hpp"  // generated from gpu/gl/shaders/ (CMakeLists.txt)

#include <string>

namespace mbi::gpu::shaders {

// Its body is gpu/gl/shaders/evaluate.glsl (shared with the browser page); before it, the
// fetches from texture buffers.
inline const std::string evaluate_vs = R"(
uniform samplerBuffer bezier;     // displacement control points, K per element
uniform samplerBuffer gradients;  // barycentric basis gradients, D + 1 per element
vec3 bezier_point(int i) { return texelFetch(bezier, i).xyz; }
vec3 basis_gradient(int i) { return texelFetch(gradients, i).xyz; }
)" + std::string(evaluate_glsl);

}  // namespace mbi::gpu::shaders
