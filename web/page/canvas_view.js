// A view drawn on a 2D canvas, for browsers without WebGL2: the triangles facing the camera,
// projected in script, sorted back to front and filled flat-shaded in the view's tint or the
// crease colours (a face's mean of its corners'); the contact's colliders in translucent grey
// over them.
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const unit = (a) => { const s = 1 / Math.hypot(a[0], a[1], a[2]); return [a[0] * s, a[1] * s, a[2] * s]; };

export class CanvasView {
  constructor(canvas, tint) {
    this.ctx = canvas.getContext('2d');
    this.tint = tint;
    this.triangles = new Uint32Array(0);
    this.colliders = { positions: new Float32Array(0), triangles: new Uint32Array(0) };
  }

  setTriangles(triangles) { this.triangles = Uint32Array.from(triangles); }

  setColliders(positions, indices) {
    this.colliders = { positions: Float32Array.from(positions), triangles: Uint32Array.from(indices) };
  }

  // frame: { positions, colors, colliders }: x y z floats per vertex; RGB floats per vertex or
  // null; whether to draw the colliders.
  draw(frame, camera) {
    const ctx = this.ctx, w = ctx.canvas.width, h = ctx.canvas.height;
    ctx.fillStyle = 'rgb(245,245,242)';
    ctx.fillRect(0, 0, w, h);
    this.paint(frame.positions, this.triangles, frame.colors, this.tint, camera);
    if (!frame.colliders || !this.colliders.triangles.length) return;
    ctx.globalAlpha = 0.45;
    this.paint(this.colliders.positions, this.colliders.triangles, null, [0.55, 0.57, 0.6], camera, false);
    ctx.globalAlpha = 1;
  }

  // Fills the triangles t of `positions` that face the camera, back to front; `edges`: their
  // outlines too, hiding the seams between opaque triangles.
  paint(positions, t, colors, tint0, camera, edges = true) {
    const ctx = this.ctx, w = ctx.canvas.width, h = ctx.canvas.height;
    const m = camera.matrix(w, h), eye = camera.eye();
    const n = positions.length / 3;
    const sx = new Float32Array(n), sy = new Float32Array(n), sz = new Float32Array(n);
    for (let i = 0; i < n; ++i) {
      const x = positions[3 * i], y = positions[3 * i + 1], z = positions[3 * i + 2];
      const cw = m[3] * x + m[7] * y + m[11] * z + m[15];
      sx[i] = ((m[0] * x + m[4] * y + m[8] * z + m[12]) / cw + 1) * 0.5 * w;
      sy[i] = (1 - (m[1] * x + m[5] * y + m[9] * z + m[13]) / cw) * 0.5 * h;
      sz[i] = cw;
    }
    const faces = [];
    for (let f = 0; f < t.length; f += 3) {
      const a = t[f], b = t[f + 1], c = t[f + 2];
      if ((sx[b] - sx[a]) * (sy[c] - sy[a]) - (sy[b] - sy[a]) * (sx[c] - sx[a]) >= 0) continue;  // back
      faces.push(f);
    }
    faces.sort((f, g) => (sz[t[g]] + sz[t[g + 1]] + sz[t[g + 2]]) - (sz[t[f]] + sz[t[f + 1]] + sz[t[f + 2]]));
    const p = (i) => [positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]];
    for (const f of faces) {
      const a = p(t[f]), b = p(t[f + 1]), c = p(t[f + 2]);
      const nrm = unit(cross(sub(b, a), sub(c, a)));
      const d = Math.abs(dot(nrm, unit(sub(eye, a))));
      const k = 0.2 + 0.8 * d;
      const tint = colors ? [0, 1, 2].map((i) => (colors[3 * t[f] + i] + colors[3 * t[f + 1] + i] + colors[3 * t[f + 2] + i]) / 3)
        : tint0;
      ctx.fillStyle = `rgb(${255 * tint[0] * k | 0},${255 * tint[1] * k | 0},${255 * tint[2] * k | 0})`;
      ctx.strokeStyle = ctx.fillStyle;
      ctx.beginPath();
      ctx.moveTo(sx[t[f]], sy[t[f]]);
      ctx.lineTo(sx[t[f + 1]], sy[t[f + 1]]);
      ctx.lineTo(sx[t[f + 2]], sy[t[f + 2]]);
      ctx.closePath();
      ctx.fill();
      if (edges) ctx.stroke();
    }
  }
}
