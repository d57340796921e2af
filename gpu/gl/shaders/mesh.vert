// The dense surface from the evaluator's buffers (rest + displacement, GPU normals); with
// VERTEX_COLOR defined, a colour per vertex (location 3) instead of the uniform colour.
layout(location = 0) in vec3 rest;
layout(location = 1) in vec3 displacement;
layout(location = 2) in vec3 normal;
#ifdef VERTEX_COLOR
layout(location = 3) in vec3 color;
out vec3 v_color;
#endif
uniform mat4 view_projection;
out vec3 v_normal;
void main() {
  v_normal = normal;
#ifdef VERTEX_COLOR
  v_color = color;
#endif
  gl_Position = view_projection * vec4(rest + displacement, 1.0);
}
