// 2D: the warped picture; texture coordinates from the rest pixel positions.
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
