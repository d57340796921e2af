// Headlight Lambert + ambient shading (creases show as shading jumps), two-sided.
in vec3 v_normal;
#ifdef VERTEX_COLOR
in vec3 v_color;
#else
uniform vec3 color;
#endif
uniform vec3 eye_direction;  // from the eye into the scene
out vec4 frag;
void main() {
#ifdef VERTEX_COLOR
  vec3 c = v_color;
#else
  vec3 c = color;
#endif
  vec3 n = normalize(v_normal);
  float lambert = abs(dot(n, -eye_direction));
  frag = vec4(c * (0.25 + 0.75 * lambert), 1.0);
}
