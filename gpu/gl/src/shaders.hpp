#pragma once
// GLSL sources of mbi::gpu (GLSL 3.30 core: transform feedback, integer attributes and texture
// buffers, no compute shaders). "#version" and "#define D <dim>" are prepended.
namespace mbi::gpu::shaders {

// Evaluation pass: displacement and normal of one dense point from its element's quadratic
// Bezier simplex (K = (D+1)(D+2)/2 control points: the D+1 vertices, then the edges in the
// order of interp::bezier_edges). Same arithmetic as interp/src/evaluate.cpp.
inline const char* evaluate_vs = R"(
const int K = (D + 1) * (D + 2) / 2;
const int E = D * (D + 1) / 2;
layout(location = 0) in int element;
layout(location = 1) in vec4 bary;
layout(location = 2) in vec3 rest_normal;
uniform samplerBuffer bezier;     // displacement control points, K per element
uniform samplerBuffer gradients;  // barycentric basis gradients, D + 1 per element
uniform int with_normals;
out vec3 tf_displacement;
out vec3 tf_normal;
#if D == 3
const ivec2 edges[6] = ivec2[6](ivec2(0, 1), ivec2(0, 2), ivec2(0, 3), ivec2(1, 2), ivec2(1, 3), ivec2(2, 3));
#else
const ivec2 edges[3] = ivec2[3](ivec2(0, 1), ivec2(0, 2), ivec2(1, 2));
#endif
void main() {
  float b[D + 1];
  for (int k = 0; k <= D; ++k) b[k] = bary[k];
  vec3 x = vec3(0.0);
  vec3 g[D + 1];
  int base = element * K;
  for (int k = 0; k <= D; ++k) {
    vec3 p = texelFetch(bezier, base + k).xyz;
    x += b[k] * b[k] * p;
    g[k] = 2.0 * b[k] * p;
  }
  for (int s = 0; s < E; ++s) {
    int i = edges[s].x, j = edges[s].y;
    vec3 q = texelFetch(bezier, base + D + 1 + s).xyz;
    x += 2.0 * b[i] * b[j] * q;
    g[i] += 2.0 * b[j] * q;
    g[j] += 2.0 * b[i] * q;
  }
  tf_displacement = x;
  tf_normal = vec3(0.0);
  if (with_normals != 0) {
    // J = I + sum_k g_k a_k^T (the rest map is the identity); n' ~ cof(J) n
    mat3 J = mat3(1.0);
    for (int k = 0; k <= D; ++k) {
      vec3 a = texelFetch(gradients, element * (D + 1) + k).xyz;
      J += outerProduct(g[k], a);
    }
#if D == 3
    vec3 o = mat3(cross(J[1], J[2]), cross(J[2], J[0]), cross(J[0], J[1])) * rest_normal;
#else
    vec3 o = vec3(J[1][1] * rest_normal.x - J[0][1] * rest_normal.y,
                  -J[1][0] * rest_normal.x + J[0][0] * rest_normal.y, 0.0);
#endif
    float len = length(o);
    tf_normal = len > 0.0 ? o / len : vec3(0.0);
  }
  gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
)";

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
