// A view drawn with WebGL2: the dense triangles, flat-shaded from screen-space derivatives
// (creases show as they are), lit from the camera, in the view's tint or the crease colours;
// the contact's colliders, when there are any, in translucent grey over them.
// Positions are rest + displacement: from script (the CPU path: the positions, no displacement)
// or from the GPU pass's buffers (gpu_evaluator.js), which stay on the GPU.
import { GpuEvaluator } from './gpu_evaluator.js';
import { program } from './gl_program.js';

const VS = `#version 300 es
uniform mat4 mvp;
layout(location = 0) in vec3 rest;
layout(location = 1) in vec3 displacement;
layout(location = 2) in vec3 color;
out vec3 world;
out vec3 tint;
void main() {
  world = rest + displacement;
  tint = color;
  gl_Position = mvp * vec4(world, 1.0);
}`;
const FS = `#version 300 es
precision highp float;
uniform vec3 eye;
uniform float opacity;
in vec3 world;
in vec3 tint;
out vec4 color;
void main() {
  vec3 n = normalize(cross(dFdx(world), dFdy(world)));
  vec3 l = normalize(eye - world);
  float d = abs(dot(n, l));
  color = vec4(tint * (0.2 + 0.8 * d) + vec3(0.25) * pow(d, 40.0), opacity);
}`;

export class GlView {
  // null when the canvas has no WebGL2.
  static create(canvas, tint) {
    const gl = canvas.getContext('webgl2', { antialias: true, preserveDrawingBuffer: true });
    return gl ? new GlView(gl, tint) : null;
  }

  constructor(gl, tint) {
    this.gl = gl;
    this.tint = tint;
    this.program = program(gl, VS, FS);
    this.vao = gl.createVertexArray();
    this.positions = gl.createBuffer();
    this.colors = gl.createBuffer();
    this.indices = gl.createBuffer();
    this.count = 0;
    this.gpu = null;
    this.colliders = { vao: gl.createVertexArray(), positions: gl.createBuffer(), indices: gl.createBuffer(), count: 0 };
  }

  // The GPU pass in this view's context from the pass's GLSL body; '' or why it failed.
  enableGpu(body) {
    try {
      this.gpu = new GpuEvaluator(this.gl, body);
      return '';
    } catch (e) {
      this.gpu = null;
      return String(e.message || e);
    }
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
    gl.bindVertexArray(null);
    this.count = triangles.length;
  }

  // The colliders' triangles: x y z floats per vertex, 3 indices each (none: empty arrays).
  setColliders(positions, indices) {
    const gl = this.gl, c = this.colliders;
    gl.bindVertexArray(c.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, c.positions);
    gl.bufferData(gl.ARRAY_BUFFER, positions, gl.DYNAMIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, c.indices);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, new Uint32Array(indices), gl.DYNAMIC_DRAW);
    gl.bindVertexArray(null);
    gl.bindBuffer(gl.ARRAY_BUFFER, null);
    c.count = indices.length;
  }

  // frame: { positions } (CPU: x y z floats per vertex) or { gpu: true } (the pass's buffers),
  // colors (RGB floats per vertex) or null for the tint, colliders: whether to draw them.
  draw(frame, camera) {
    const gl = this.gl, c = gl.canvas;
    gl.viewport(0, 0, c.width, c.height);
    gl.clearColor(0.96, 0.96, 0.95, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(this.program);
    gl.bindVertexArray(this.vao);
    if (frame.gpu) {
      this.attribute(0, this.gpu.rest);
      this.attribute(1, this.gpu.displacement);
    } else {
      gl.bindBuffer(gl.ARRAY_BUFFER, this.positions);
      gl.bufferData(gl.ARRAY_BUFFER, frame.positions, gl.DYNAMIC_DRAW);
      this.attribute(0, this.positions);
      gl.disableVertexAttribArray(1);
      gl.vertexAttrib3f(1, 0, 0, 0);
    }
    if (frame.colors) {
      gl.bindBuffer(gl.ARRAY_BUFFER, this.colors);
      gl.bufferData(gl.ARRAY_BUFFER, frame.colors, gl.DYNAMIC_DRAW);
      this.attribute(2, this.colors);
    } else {
      gl.disableVertexAttribArray(2);
      gl.vertexAttrib3f(2, ...this.tint);
    }
    gl.uniformMatrix4fv(gl.getUniformLocation(this.program, 'mvp'), false, camera.matrix(c.width, c.height));
    gl.uniform3fv(gl.getUniformLocation(this.program, 'eye'), camera.eye());
    gl.uniform1f(gl.getUniformLocation(this.program, 'opacity'), 1);
    gl.drawElements(gl.TRIANGLES, this.count, gl.UNSIGNED_INT, 0);
    if (frame.colliders && this.colliders.count) this.drawColliders();
    gl.bindVertexArray(null);
    gl.bindBuffer(gl.ARRAY_BUFFER, null);
  }

  // Translucent over the model, depth tested against it but not hiding one another.
  drawColliders() {
    const gl = this.gl;
    gl.bindVertexArray(this.colliders.vao);
    gl.vertexAttrib3f(1, 0, 0, 0);
    gl.vertexAttrib3f(2, 0.55, 0.57, 0.6);
    gl.uniform1f(gl.getUniformLocation(this.program, 'opacity'), 0.45);
    gl.enable(gl.BLEND);
    gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
    gl.depthMask(false);
    gl.drawElements(gl.TRIANGLES, this.colliders.count, gl.UNSIGNED_INT, 0);
    gl.depthMask(true);
    gl.disable(gl.BLEND);
  }

  attribute(loc, buffer) {
    const gl = this.gl;
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    gl.enableVertexAttribArray(loc);
    gl.vertexAttribPointer(loc, 3, gl.FLOAT, false, 0, 0);
  }
}
