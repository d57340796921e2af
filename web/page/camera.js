// An orbiting perspective camera shared by the two views: view and projection matrices
// (column-major, for WebGL), world points to pixels (the 2D fallback), pixels to rays (pokes:
// the module picks, pulls and moves the drag plane with mbi::interact, as the viewer does).
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const unit = (a) => scale(a, 1 / Math.hypot(a[0], a[1], a[2]));
export { sub, add, scale, dot, cross, unit };

export class Camera {
  // up: the model's up axis; yaw and pitch in radians about it.
  constructor(center, size, up, yaw = 0.6, pitch = 0.25) {
    this.center = center;
    this.size = size;
    this.up = unit(up);
    const side = Math.abs(this.up[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
    this.a = unit(cross(this.up, side));
    this.b = cross(this.up, this.a);
    this.yaw = yaw;
    this.pitch = pitch;
    this.distance = 1.8 * size;
    this.fov = 0.6;  // vertical, radians
  }

  eye() {
    const c = Math.cos(this.pitch);
    const dir = add(add(scale(this.a, c * Math.cos(this.yaw)), scale(this.b, c * Math.sin(this.yaw))),
                    scale(this.up, Math.sin(this.pitch)));
    return add(this.center, scale(dir, this.distance));
  }

  // The camera's frame: forward (into the picture), right and up, unit vectors.
  frame() {
    const f = unit(sub(this.center, this.eye()));
    const r = unit(cross(f, this.up));
    return { f, r, u: cross(r, f) };
  }

  orbit(dx, dy) {
    this.yaw -= dx * 0.01;
    this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch + dy * 0.01));
  }

  zoom(dy) { this.distance *= Math.exp(dy * 0.001); }

  // Column-major projection * view for a width x height viewport.
  matrix(width, height) {
    const { f, r, u } = this.frame();
    const e = this.eye();
    const near = 0.01 * this.size, far = 100 * this.size;
    const t = 1 / Math.tan(this.fov / 2), asp = width / height;
    const view = [r[0], u[0], -f[0], 0, r[1], u[1], -f[1], 0, r[2], u[2], -f[2], 0,
                  -dot(r, e), -dot(u, e), dot(f, e), 1];
    const proj = [t / asp, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) / (near - far), -1,
                  0, 0, 2 * far * near / (near - far), 0];
    const m = new Float32Array(16);
    for (let c = 0; c < 4; ++c)
      for (let row = 0; row < 4; ++row) {
        let s = 0;
        for (let k = 0; k < 4; ++k) s += proj[k * 4 + row] * view[c * 4 + k];
        m[c * 4 + row] = s;
      }
    return m;
  }

  // The ray through pixel (x, y) of a width x height view (y down).
  ray(x, y, width, height) {
    const { f, r, u } = this.frame();
    const t = Math.tan(this.fov / 2);
    const px = (2 * x / width - 1) * t * width / height, py = (1 - 2 * y / height) * t;
    return { origin: this.eye(), direction: add(f, add(scale(r, px), scale(u, py))) };
  }
}
