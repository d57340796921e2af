// The views' camera: mbi::interact::PerspectiveCamera in the module (web/api/camera.cpp), the
// viewer's library, so the page holds no camera maths: an orbiting perspective camera, its
// projection * view matrix (column-major, for WebGL) and rays through pixels (pokes).
import M from './module.js';

const fail = () => { throw new Error('camera: ' + M.UTF8ToString(M._mbi_camera_error())); };
const doubles = (ptr, n) => (ptr ? Array.from(new Float64Array(M.HEAPF64.buffer, ptr, n)) : fail());
const released = new FinalizationRegistry((id) => M._mbi_camera_delete(id));

export class Camera {
  // up: the model's up axis; yaw and pitch in radians about it (PerspectiveCamera's defaults).
  constructor(center, size, up, yaw = 0.6, pitch = 0.25) {
    this.id = M._mbi_camera_new(...center, size, ...up, yaw, pitch);
    if (this.id < 0) fail();
    released.register(this, this.id);
  }

  eye() { return doubles(M._mbi_camera_pose(this.id), 3); }

  // The camera's frame: forward (into the picture), right and up, unit vectors.
  frame() {
    const p = doubles(M._mbi_camera_pose(this.id), 12);
    return { f: p.slice(3, 6), r: p.slice(6, 9), u: p.slice(9, 12) };
  }

  orbit(dx, dy) { M._mbi_camera_orbit(this.id, dx, dy); }

  zoom(dy) { M._mbi_camera_zoom(this.id, dy); }

  // Column-major projection * view for a width x height viewport.
  matrix(width, height) {
    const ptr = M._mbi_camera_matrix(this.id, width, height);
    return ptr ? new Float32Array(M.HEAPF32.buffer, ptr, 16).slice() : fail();
  }

  // The ray through pixel (x, y) of a width x height view (y down).
  ray(x, y, width, height) {
    const r = doubles(M._mbi_camera_ray(this.id, x, y, width, height), 6);
    return { origin: r.slice(0, 3), direction: r.slice(3, 6) };
  }
}
