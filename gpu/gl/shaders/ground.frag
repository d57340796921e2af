// Grid lines one pixel wide whatever the distance (fwidth), every tenth darker; the shadow a
// rounded rectangle whose edge fades over `soft`; the square's edge fades into the background.
in vec2 p;
uniform float half_side, spacing, soft;
uniform vec2 shadow_center, shadow_half;
uniform vec3 background;
out vec4 frag;
float lines(vec2 q) {
  vec2 g = abs(fract(q - 0.5) - 0.5) / max(fwidth(q), vec2(1e-6));
  return 1.0 - min(min(g.x, g.y), 1.0);
}
void main() {
  vec2 q = p / spacing;
  float grid = max(0.5 * lines(q), lines(q / 10.0));
  float d = length(max(abs(p - shadow_center) - shadow_half, 0.0));
  float shadow = 0.42 * (1.0 - smoothstep(0.0, soft, d));
  vec3 ground = vec3(0.9, 0.9, 0.89) * (1.0 - 0.12 * grid) * (1.0 - shadow);
  float fade = smoothstep(half_side, 0.55 * half_side, length(p));
  frag = vec4(mix(background, ground, fade), 1.0);
}
