// The dense points evaluated on the GPU with WebGL2: the transform-feedback pass of gpu/gl, its
// body the same file (evaluate.glsl, fetched beside the page), the per-element Bezier points in
// a 2D float texture (WebGL2 has no texture buffers). The pass writes the displacement buffer
// that the view draws (rest + displacement), so nothing comes back to script unless asked.
import { program } from './gl_program.js';

const PRELUDE = `#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
#define D 3
uniform sampler2D bezier;     // displacement control points, K per element, row after row
uniform sampler2D gradients;  // basis gradients: a zero texel (the page shades without normals)
vec3 texel(sampler2D s, int i) {
  int w = textureSize(s, 0).x;
  return texelFetch(s, ivec2(i % w, i / w), 0).xyz;
}
vec3 bezier_point(int i) { return texel(bezier, i); }
vec3 basis_gradient(int i) { return texel(gradients, i); }
`;
const FS = `#version 300 es
precision highp float;
out vec4 color;
void main() { color = vec4(0.0); }`;
const WIDTH = 1024;  // texels per row of the Bezier texture

function floatTexture(gl, width, height) {
  const t = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, t);
  gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, width, height);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);  // float: not filterable
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  return t;
}

export class GpuEvaluator {
  // Throws (with the compiler's or linker's message) where the pass cannot be built.
  constructor(gl, body) {
    this.gl = gl;
    this.program = program(gl, PRELUDE + body, FS, ['tf_displacement']);
    this.feedback = gl.createTransformFeedback();
    this.gradients = floatTexture(gl, 1, 1);
    gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, 1, 1, gl.RGBA, gl.FLOAT, new Float32Array(4));
    this.points = 0;
  }

  // The dense points: per point its element (Int32Array), barycentric coordinates (4 floats)
  // and rest position (3 floats); `rows` Bezier points per frame.
  setPoints(elements, bary, rest, rows) {
    const gl = this.gl;
    this.release();
    this.points = elements.length;
    this.vao = gl.createVertexArray();
    gl.bindVertexArray(this.vao);
    this.elements = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.elements);
    gl.bufferData(gl.ARRAY_BUFFER, elements, gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribIPointer(0, 1, gl.INT, 0, 0);  // an integer attribute
    this.bary = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.bary);
    gl.bufferData(gl.ARRAY_BUFFER, bary, gl.STATIC_DRAW);
    gl.enableVertexAttribArray(1);
    gl.vertexAttribPointer(1, 4, gl.FLOAT, false, 0, 0);
    gl.bindVertexArray(null);
    this.rest = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.rest);
    gl.bufferData(gl.ARRAY_BUFFER, rest, gl.STATIC_DRAW);
    this.displacement = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.displacement);
    gl.bufferData(gl.ARRAY_BUFFER, 4 * rest.length, gl.DYNAMIC_COPY);
    gl.bindBuffer(gl.ARRAY_BUFFER, null);
    this.height = Math.max(1, Math.ceil(rows / WIDTH));
    this.staging = new Float32Array(4 * WIDTH * this.height);
    this.bezier = floatTexture(gl, WIDTH, this.height);
  }

  release() {
    const gl = this.gl;
    if (!this.vao) return;
    [this.elements, this.bary, this.rest, this.displacement].forEach((b) => gl.deleteBuffer(b));
    gl.deleteTexture(this.bezier);
    gl.deleteVertexArray(this.vao);
    this.vao = null;
  }

  // One frame: the Bezier points minus the rest shape's (x y z 0 per point) in, the
  // displacements out into this.displacement.
  evaluate(texels) {
    const gl = this.gl;
    this.staging.set(texels);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, this.bezier);
    gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, WIDTH, this.height, gl.RGBA, gl.FLOAT, this.staging);
    gl.activeTexture(gl.TEXTURE1);
    gl.bindTexture(gl.TEXTURE_2D, this.gradients);
    gl.useProgram(this.program);
    gl.uniform1i(gl.getUniformLocation(this.program, 'bezier'), 0);
    gl.uniform1i(gl.getUniformLocation(this.program, 'gradients'), 1);
    gl.uniform1i(gl.getUniformLocation(this.program, 'with_normals'), 0);
    gl.bindVertexArray(this.vao);
    // the output may be bound nowhere else during the pass (WebGL2's rule), nor after it
    gl.bindBuffer(gl.ARRAY_BUFFER, null);
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, this.feedback);
    gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, this.displacement);
    gl.enable(gl.RASTERIZER_DISCARD);
    gl.beginTransformFeedback(gl.POINTS);
    gl.drawArrays(gl.POINTS, 0, this.points);
    gl.endTransformFeedback();
    gl.disable(gl.RASTERIZER_DISCARD);
    gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, null);
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, null);
    gl.bindVertexArray(null);
    gl.activeTexture(gl.TEXTURE0);
  }

  // The first `count` floats of the displacements, read back (waits for the pass).
  read(count = 3 * this.points) {
    const gl = this.gl, out = new Float32Array(count);
    gl.bindBuffer(gl.COPY_READ_BUFFER, this.displacement);
    gl.getBufferSubData(gl.COPY_READ_BUFFER, 0, out);
    gl.bindBuffer(gl.COPY_READ_BUFFER, null);
    return out;
  }

  // Positions (rest + displacement), read back through the transform feedback buffer.
  positions(rest) {
    const d = this.read();
    for (let i = 0; i < d.length; ++i) d[i] += rest[i];
    return d;
  }
}
