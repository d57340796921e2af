// The viewer's ground: a square of half side `half_side` in the plane (center; e1, e2).
layout(location = 0) in vec2 corner;
uniform mat4 view_projection;
uniform vec3 center, e1, e2;
uniform float half_side;
out vec2 p;
void main() {
  p = corner * half_side;
  gl_Position = view_projection * vec4(center + p.x * e1 + p.y * e2, 1.0);
}
