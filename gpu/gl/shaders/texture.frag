// 2D: the picture at the rest position's texture coordinates.
in vec2 uv;
uniform sampler2D image;
out vec4 frag;
void main() { frag = vec4(texture(image, uv).rgb, 1.0); }
