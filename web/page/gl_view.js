// A view drawn with WebGL2: the dense triangles, flat-shaded from screen-space derivatives
// (creases show as they are), lit from the camera.
const VS = `#version 300 es
uniform mat4 mvp;
in vec3 position;
out vec3 world;
void main() { world = position; gl_Position = mvp * vec4(position, 1.0); }`;
const FS = `#version 300 es
precision highp float;
uniform vec3 eye;
uniform vec3 tint;
in vec3 world;
out vec4 color;
void main() {
  vec3 n = normalize(cross(dFdx(world), dFdy(world)));
  vec3 l = normalize(eye - world);
  float d = abs(dot(n, l));
  color = vec4(tint * (0.2 + 0.8 * d) + vec3(0.25) * pow(d, 40.0), 1.0);
}`;

function shader(gl, type, text) {
  const s = gl.createShader(type);
  gl.shaderSource(s, text);
  gl.compileShader(s);
  if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
  return s;
}

export class GlView {
  // null when the canvas has no WebGL2.
  static create(canvas, tint) {
    const gl = canvas.getContext('webgl2', { antialias: true, preserveDrawingBuffer: true });
    return gl ? new GlView(gl, tint) : null;
  }

  constructor(gl, tint) {
    this.gl = gl;
    this.tint = tint;
    const p = gl.createProgram();
    gl.attachShader(p, shader(gl, gl.VERTEX_SHADER, VS));
    gl.attachShader(p, shader(gl, gl.FRAGMENT_SHADER, FS));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    this.program = p;
    this.vao = gl.createVertexArray();
    this.positions = gl.createBuffer();
    this.indices = gl.createBuffer();
    this.count = 0;
  }

  // The GPU or software renderer behind the context, where the browser tells.
  renderer() {
    const gl = this.gl, info = gl.getExtension('WEBGL_debug_renderer_info');
    return gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER);
  }

  setTriangles(triangles) {
    const gl = this.gl;
    gl.bindVertexArray(this.vao);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.indices);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, new Uint32Array(triangles), gl.STATIC_DRAW);
    this.count = triangles.length;
  }

  draw(positions, camera) {
    const gl = this.gl, c = gl.canvas;
    gl.viewport(0, 0, c.width, c.height);
    gl.clearColor(0.96, 0.96, 0.95, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(this.program);
    gl.bindVertexArray(this.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.positions);
    gl.bufferData(gl.ARRAY_BUFFER, positions, gl.DYNAMIC_DRAW);
    const at = gl.getAttribLocation(this.program, 'position');
    gl.enableVertexAttribArray(at);
    gl.vertexAttribPointer(at, 3, gl.FLOAT, false, 0, 0);
    gl.uniformMatrix4fv(gl.getUniformLocation(this.program, 'mvp'), false, camera.matrix(c.width, c.height));
    gl.uniform3fv(gl.getUniformLocation(this.program, 'eye'), camera.eye());
    gl.uniform3fv(gl.getUniformLocation(this.program, 'tint'), this.tint);
    gl.drawElements(gl.TRIANGLES, this.count, gl.UNSIGNED_INT, 0);
  }
}
