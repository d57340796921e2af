// The evaluation pass of mbi::gpu and of the browser page (web/page/gpu_evaluator.js): the
// displacement and normal of one dense point from its element's quadratic Bezier simplex
// (K = (D+1)(D+2)/2 control points: the D+1 vertices, then the edges in the order of
// interp::bezier_edges). Same arithmetic as interp/src/evaluate.cpp. Each build prepends
// "#version", "#define D <dim>" and the two fetches, bezier_point(i) and basis_gradient(i)
// (a texture buffer natively, a 2D float texture in WebGL2, which has no texture buffers).
const int K = (D + 1) * (D + 2) / 2;
const int E = D * (D + 1) / 2;
layout(location = 0) in int element;
layout(location = 1) in vec4 bary;
layout(location = 2) in vec3 rest_normal;
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
    vec3 p = bezier_point(base + k);
    x += b[k] * b[k] * p;
    g[k] = 2.0 * b[k] * p;
  }
  for (int s = 0; s < E; ++s) {
    int i = edges[s].x, j = edges[s].y;
    vec3 q = bezier_point(base + D + 1 + s);
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
      vec3 a = basis_gradient(element * (D + 1) + k);
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
