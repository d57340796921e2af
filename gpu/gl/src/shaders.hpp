#pragma once
// GLSL sources of mbi::gpu (GLSL 3.30 core: transform feedback, integer attributes and texture
// buffers, no compute shaders). "#version" and "#define D <dim>" are prepended.
#include "evaluate_glsl.hpp"  // generated from gpu/gl/shaders/evaluate.glsl (CMakeLists.txt)

#include <string>

namespace mbi::gpu::shaders {

// Evaluation pass: its body is gpu/gl/shaders/evaluate.glsl (shared with the browser page),
// embedded at configure time as evaluate_glsl; before it, the fetches from texture buffers.
inline const std::string evaluate_vs = R"(
uniform samplerBuffer bezier;     // displacement control points, K per element
uniform samplerBuffer gradients;  // barycentric basis gradients, D + 1 per element
vec3 bezier_point(int i) { return texelFetch(bezier, i).xyz; }
vec3 basis_gradient(int i) { return texelFetch(gradients, i).xyz; }
)" + std::string(evaluate_glsl);

// Renderer: the dense mesh from the evaluator's buffers (rest + displacement, GPU normals),
// orthographic camera, headlight Lambert + ambient shading (creases show as shading jumps).
inline const char* mesh_vs = R"(
layout(location = 0) in vec3 rest;
layout(location = 1) in vec3 displacement;
layout(location = 2) in vec3 normal;
uniform mat4 view_projection;
out vec3 v_normal;
void main() {
  v_normal = normal;
  gl_Position = view_projection * vec4(rest + displacement, 1.0);
}
)";

inline const char* mesh_fs = R"(
in vec3 v_normal;
uniform vec3 color;
uniform vec3 eye_direction;  // from the eye into the scene
out vec4 frag;
void main() {
  vec3 n = normalize(v_normal);
  float lambert = abs(dot(n, -eye_direction));
  frag = vec4(color * (0.25 + 0.75 * lambert), 1.0);
}
)";

// 2D: the warped picture; texture coordinates from the rest pixel positions.
inline const char* texture_vs = R"(
layout(location = 0) in vec3 rest;
layout(location = 1) in vec3 displacement;
uniform mat4 view_projection;
uniform vec3 origin;     // the evaluator's origin (rest = rest pixel position - origin)
uniform vec2 image_size;
out vec2 uv;
void main() {
  vec3 r = rest + origin;
  uv = vec2(r.x / image_size.x, r.y / image_size.y);
  gl_Position = view_projection * vec4(rest + displacement, 1.0);
}
)";

inline const char* texture_fs = R"(
in vec2 uv;
uniform sampler2D image;
out vec4 frag;
void main() { frag = vec4(texture(image, uv).rgb, 1.0); }
)";

// Lines (control-mesh wireframe) in a flat colour.
inline const char* line_vs = R"(
layout(location = 0) in vec3 position;
uniform mat4 view_projection;
void main() { gl_Position = view_projection * vec4(position, 1.0); }
)";

inline const char* line_fs = R"(
uniform vec3 color;
out vec4 frag;
void main() { frag = vec4(color, 1.0); }
)";

}  // namespace mbi::gpu::shaders
