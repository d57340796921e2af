// A clay matcap: a key light from the upper left, a sky-to-ground fill, a soft rim and a small
// highlight, all from the normal in camera space (x right, y up, z toward the eye). Two-sided:
// models with inward or mixed normals look the same.
in vec3 v_normal;
uniform vec3 color;
out vec4 frag;
void main() {
  vec3 n = normalize(v_normal);
  if (n.z < 0.0) n = -n;
  vec3 key = normalize(vec3(-0.45, 0.6, 0.65));
  float diffuse = max(dot(n, key), 0.0);
  vec3 fill = mix(vec3(0.32, 0.3, 0.28), vec3(0.55, 0.6, 0.68), 0.5 + 0.5 * n.y);
  // powers by multiplication: pow() is costly on a software renderer
  float r = 1.0 - n.z, rim = r * r * r;
  float h = max(dot(reflect(-key, n), vec3(0.0, 0.0, 1.0)), 0.0), h2 = h * h, h4 = h2 * h2, h8 = h4 * h4;
  vec3 c = color * (fill + 0.75 * diffuse) + 0.18 * (h8 * h8 * h8) + 0.12 * rim;
  frag = vec4(clamp(c, 0.0, 1.0), 1.0);
}
