// The viewer's surface in its clay material: the normal turned into camera space.
layout(location = 0) in vec3 rest;
layout(location = 1) in vec3 displacement;
layout(location = 2) in vec3 normal;
uniform mat4 view_projection;
uniform mat3 view_rotation;
out vec3 v_normal;
void main() {
  v_normal = view_rotation * normal;
  gl_Position = view_projection * vec4(rest + displacement, 1.0);
}
