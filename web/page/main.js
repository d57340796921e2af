// The page: the WebAssembly module (mbi-web.js, the C API of web/api/api.h), two views (BI,
// modified-BI) drawn with WebGL2 or, without it, a 2D canvas, mouse pokes and the controls.
// Scenes with contact at the dense surface run the module's contact (the frame pipeline's, as
// `mbi run`); the page draws their colliders and says how many dense vertices touch.
// The dense points are evaluated on the GPU (WebGL2 transform feedback, gpu_evaluator.js) where
// the pass builds, else (or when asked: ?eval=cpu, the evaluator switch) on the CPU in wasm.
// window.mbiPage exposes the state to the browser test (web/test).
import M from './module.js';
import { Camera } from './camera.js';
import { GlView } from './gl_view.js';
import { CanvasView } from './canvas_view.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);

// The API; the calls that change the model are journaled, so that a test can replay them in
// the native build (mbi-web-twin replay).
const journal = [];
const call = (name, ret, n) => {
  const f = M.cwrap('mbi_' + name, ret, Array(n).fill('number'));
  return (...a) => { journal.push([name, ...a].join(' ')); return f(...a); };
};
const api = {
  loadScene: call('load_scene', 'number', 1), step: call('step', 'number', 0),
  reset: call('reset', 'number', 0), setMethod: call('set_method', 'number', 1),
  setAlpha: call('set_alpha', 'number', 1), grab: call('grab', 'number', 7),
  move: call('move', null, 6), release: call('release', null, 0),
  setCpuEvaluation: call('set_cpu_evaluation', 'number', 1),
  alpha: M.cwrap('mbi_alpha', 'number', []), error: M.cwrap('mbi_error', 'string', []), description: M.cwrap('mbi_description', 'string', []),
  sceneName: M.cwrap('mbi_scene_name', 'string', ['number']), sceneProblem: M.cwrap('mbi_scene_problem', 'string', ['number']),
  loadSceneText: M.cwrap('mbi_load_scene_text', 'number', ['number', 'number', 'string']),
  touching: () => M._mbi_touching_points(), colliders: () => M._mbi_collider_count(),
};

// The scene list: the scene files of scenes/ built into the module; those the page cannot run
// are shown, greyed, with the reason.
const scenes = Array.from({ length: M._mbi_scene_count() }, (_, k) => ({ name: api.sceneName(k), problem: api.sceneProblem(k) }));
scenes.forEach((s, k) => {
  const option = new Option(s.problem ? `${s.name} (not here: ${s.problem})` : s.name, String(k));
  option.disabled = s.problem !== '';
  $('scene').add(option);
});
const TINTS = [[0.85, 0.55, 0.35], [0.35, 0.6, 0.85]];

// Drawing: WebGL2 unless missing (or ?draw=2d asks for the fallback).
const canvases = [$('view0'), $('view1')];
let views = params.get('draw') === '2d' ? [null, null] : canvases.map((c, k) => GlView.create(c, TINTS[k]));
const drawPath = views.every((v) => v) ? 'WebGL2' : '2D canvas';
if (drawPath !== 'WebGL2') views = canvases.map((c, k) => new CanvasView(c, TINTS[k]));

// Evaluation: the GPU pass (its GLSL body shared with the native build) where it builds.
let gpuProblem = 'no WebGL2';
if (drawPath === 'WebGL2') {
  const body = await (await fetch('evaluate.glsl')).text();
  gpuProblem = views.map((v) => v.enableGpu(body)).find((e) => e) || '';
}
const gpuAvailable = gpuProblem === '';

const state = { playing: params.get('play') !== '0', dirty: true, camera: null, up: [0, 0, 1],
                poking: false, drag: null, frame: 0, wasm: [], phases: null, fps: 0, drawn: [],
                sums: [0, 0, 0, 0, 0], steps: 0, gpu: false, gpuMs: 0, creases: false, creaseTop: 0,
                table: null, colliders: true };

function positions(view) {
  const n = 3 * M._mbi_vertex_count();
  return new Float32Array(M.HEAPF32.buffer, M._mbi_positions(view), n);
}

function floats(ptr, n) { return new Float32Array(M.HEAPF32.buffer, ptr, n); }

// The GPU pass of both views for the current frame (the ms to issue them, for the status line:
// the GPU runs them later).
function runGpu() {
  const t0 = performance.now(), rows = M._mbi_bezier_rows();
  views.forEach((v, k) => v.gpu.evaluate(floats(M._mbi_bezier_texels(k), 4 * rows)));
  state.gpuMs = performance.now() - t0;
}

// The discontinuity table of the current frame (paper Table 2): mean and largest face energy
// of BI, of modified-BI, the number of interior faces; null where it cannot be computed.
function table() {
  const ptr = M._mbi_discontinuity();
  if (!ptr) return null;
  const t = new Float64Array(M.HEAPF64.buffer, ptr, 5);
  return { bi: t[0], biMax: t[1], modifiedBi: t[2], modifiedBiMax: t[3], faces: t[4] };
}

// The colliders as they stand at the current frame, to both views (none: empty).
function updateColliders() {
  const n = api.colliders() ? M._mbi_collider_mesh() : 0, t = n ? M._mbi_collider_triangle_count() : 0;
  const p = n ? floats(M._mbi_collider_positions(), 3 * n) : new Float32Array(0);
  const i = t ? new Int32Array(M.HEAP32.buffer, M._mbi_collider_triangles(), 3 * t) : new Int32Array(0);
  views.forEach((v) => v.setColliders(p, i));
}

// After a new frame: the GPU pass, the crease colours, the colliders, the table, a redraw.
function frameChanged() {
  if (state.gpu) runGpu();
  updateColliders();
  if (state.creases) state.creaseTop = M._mbi_update_creases();
  state.table = table();
  state.dirty = true;
}

function setEvaluator(gpu) {
  state.gpu = gpu && gpuAvailable;
  api.setCpuEvaluation(state.gpu ? 0 : 1);
  $('evaluator').value = state.gpu ? 'gpu' : 'cpu';
  frameChanged();
}

function triangles() {
  return new Int32Array(M.HEAP32.buffer, M._mbi_triangles(), 3 * M._mbi_triangle_count());
}

// After a load: both views get the triangles; the camera frames the model, its up direction
// the scene's.
function loaded() {
  const up = Array.from(new Float64Array(M.HEAPF64.buffer, M._mbi_up(), 3));
  const t = triangles();
  views.forEach((v) => v.setTriangles(t));
  if (gpuAvailable) {
    const n = M._mbi_vertex_count(), rest = floats(M._mbi_rest_positions(), 3 * n);
    const elements = new Int32Array(M.HEAP32.buffer, M._mbi_point_elements(), n);
    views.forEach((v) => v.gpu.setPoints(elements, floats(M._mbi_point_bary(), 4 * n), rest, M._mbi_bezier_rows()));
  }
  const p = positions(1), lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < p.length; ++i) {
    lo[i % 3] = Math.min(lo[i % 3], p[i]);
    hi[i % 3] = Math.max(hi[i % 3], p[i]);
  }
  const center = lo.map((l, c) => 0.5 * (l + hi[c]));
  state.camera = new Camera(center, Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]), up);
  $('alpha').value = api.alpha();  // the model's (interp's default)
  restart();
}

function restart() {
  state.frame = 0;
  state.wasm = [];
  state.sums.fill(0);
  state.steps = 0;
  api.setCpuEvaluation(state.gpu ? 0 : 1);
  frameChanged();
}

function loadScene(scene) {
  if (!api.loadScene(scene)) return show(api.error());
  $('scene').value = String(scene);
  loaded();
}

// A scene file given to the page, run as those of scenes/ are (its messages name the file).
function loadSceneText(text, name) {
  const bytes = new TextEncoder().encode(text);
  const ptr = M._malloc(bytes.length);
  M.HEAPU8.set(bytes, ptr);
  const ok = api.loadSceneText(ptr, bytes.length, name);
  M._free(ptr);
  journal.push('load_scene_text ' + name);
  if (!ok) return show('could not load the scene: ' + api.error());
  $('scene').value = '';
  show('');
  loaded();
}

function loadObj(text) {
  const bytes = new TextEncoder().encode(text);
  const ptr = M._malloc(bytes.length);
  M.HEAPU8.set(bytes, ptr);
  const ok = M._mbi_load_obj(ptr, bytes.length, 150);
  M._free(ptr);
  journal.push('load_obj');
  if (!ok) return show('could not load the OBJ: ' + api.error());
  loaded();
}

function step() {
  const t0 = performance.now();
  const f = api.step();
  state.wasm.push(performance.now() - t0);
  if (state.wasm.length > 60) state.wasm.shift();
  if (f < 0) {
    state.playing = false;
    show('the simulation stopped: ' + api.error());
  }
  state.frame = f;
  state.phases = Array.from(new Float64Array(M.HEAPF64.buffer, M._mbi_times(), 5));
  state.phases.forEach((x, k) => { state.sums[k] += x; });
  state.steps++;
  frameChanged();
}

function draw() {
  views.forEach((v, k) => v.draw({
    gpu: state.gpu, positions: state.gpu ? null : positions(k), colliders: state.colliders,
    colors: state.creases ? floats(M._mbi_crease_colors(k), 3 * M._mbi_vertex_count()) : null,
  }, state.camera));
  state.dirty = false;
  const now = performance.now();
  state.drawn.push(now);
  while (state.drawn.length > 1 && now - state.drawn[0] > 1000) state.drawn.shift();
  state.fps = state.drawn.length > 1 ? 1000 * (state.drawn.length - 1) / (now - state.drawn[0]) : 0;
}

const ms = (x) => x.toFixed(2) + ' ms';
function status() {
  const p = state.phases;
  const mean = state.wasm.length ? state.wasm.reduce((a, b) => a + b, 0) / state.wasm.length : 0;
  const evaluation = state.gpu ? `GPU (WebGL2 transform feedback), both views' passes issued in ${ms(state.gpuMs)}`
    : 'CPU (wasm)' + (gpuAvailable ? '' : `: the GPU pass is unavailable (${gpuProblem})`);
  return `${api.description()}\ndrawing: ${drawPath}    frame ${state.frame}    ${state.fps.toFixed(0)} fps\n` +
    `evaluation: ${evaluation}` + (state.creases ? `    creases: red at a gradient jump of ${state.creaseTop.toPrecision(3)}` : '') + '\n' +
    (p ? `last frame in wasm: simulation ${ms(p[0])}, solve ${ms(p[1])}, Bezier ${ms(p[2])}, ` +
         `evaluation ${state.gpu ? 'on the GPU' : ms(p[3])} (sum ${ms(p[0] + p[1] + p[2] + p[3])}); ` +
         `the other view ${state.gpu ? 'on the GPU' : ms(p[4])}\n` : '') +
    `mean step in wasm over the last ${state.wasm.length} frames (both views): ${ms(mean)}` + contactLine() + tableLine();
}

// Contact at the dense surface, as `mbi run` reports it: the vertices inside a collider.
function contactLine() {
  const n = api.colliders();
  return n ? `\ncontact at the dense surface: ${api.touching()} dense vertices touching, ${n} collider${n > 1 ? 's' : ''}` +
    (state.colliders ? ' (drawn in grey)' : '') : '';
}

// The paper's Table 2, as `mbi run` prints it: how much BI creases that modified-BI does not.
function tableLine() {
  const t = state.table;
  if (!t || !t.faces) return '';
  const e = (x) => x.toExponential(2);
  return `\nface discontinuity over ${t.faces} interior control faces (paper Table 2), mean E_F: BI ${e(t.bi)}, ` +
    `modified-BI ${e(t.modifiedBi)}` + (t.modifiedBi > 0 ? ` (${(t.bi / t.modifiedBi).toFixed(1)} times smaller)` : '');
}
let note = '';
function show(text) { note = text; }

function loop() {
  if (state.playing) step();
  if (state.dirty) draw();
  $('status').textContent = status() + (note ? '\n' + note : '');
  requestAnimationFrame(loop);
}

// Mouse: a drag that starts on the model pokes it; elsewhere it turns the view.
function rayAt(e, canvas) {
  const r = canvas.getBoundingClientRect();
  const x = (e.clientX - r.left) * canvas.width / r.width, y = (e.clientY - r.top) * canvas.height / r.height;
  const ray = state.camera.ray(x, y, canvas.width, canvas.height);
  return [...ray.origin, ...ray.direction];
}
canvases.forEach((canvas, view) => {
  canvas.addEventListener('pointerdown', (e) => {
    canvas.setPointerCapture(e.pointerId);
    state.poking = e.button === 0 && api.grab(view, ...rayAt(e, canvas)) === 1;
    state.drag = { canvas, x: e.clientX, y: e.clientY };
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!state.drag) return;
    if (state.poking) api.move(...rayAt(e, canvas));
    else state.camera.orbit(e.clientX - state.drag.x, e.clientY - state.drag.y);
    state.drag.x = e.clientX;
    state.drag.y = e.clientY;
    state.dirty = true;
  });
  canvas.addEventListener('pointerup', () => {
    if (state.poking) api.release();
    state.poking = false;
    state.drag = null;
  });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    state.camera.zoom(e.deltaY);
    state.dirty = true;
  }, { passive: false });
});

// Controls.
const setPlaying = (on) => { state.playing = on; $('play').textContent = on ? 'pause' : 'play'; };
$('play').onclick = () => setPlaying(!state.playing);
$('step').onclick = () => { setPlaying(false); step(); };
$('reset').onclick = () => { api.reset(); restart(); };
$('evaluator').onchange = (e) => setEvaluator(e.target.value === 'gpu');
$('creases').onchange = (e) => { state.creases = e.target.checked; frameChanged(); };
$('colliders').onchange = (e) => { state.colliders = e.target.checked; state.dirty = true; };
$('scene').onchange = (e) => loadScene(Number(e.target.value));
$('method').onchange = (e) => { if (!api.setMethod(Number(e.target.value))) show(api.error()); };
$('alpha').onchange = (e) => { if (!api.setAlpha(Number(e.target.value))) show(api.error()); else show(''); };
document.addEventListener('keydown', (e) => {
  if (e.target.tagName === 'INPUT') return;
  if (e.key === ' ') setPlaying(!state.playing);
  else if (e.key === 's') $('step').onclick();
  else if (e.key === 'r') $('reset').onclick();
  else return;
  e.preventDefault();
});
// A file given to the page: a scene file (.toml) or a model (OBJ).
const readFile = (file) => file && file.text().then((text) => (/\.toml$/i.test(file.name) ? loadSceneText(text, file.name) : loadObj(text)));
$('file').onchange = (e) => readFile(e.target.files[0]);
document.addEventListener('dragover', (e) => { e.preventDefault(); document.body.classList.add('dragging'); });
document.addEventListener('dragleave', () => document.body.classList.remove('dragging'));
document.addEventListener('drop', (e) => {
  e.preventDefault();
  document.body.classList.remove('dragging');
  readFile(e.dataTransfer.files[0]);
});

// A view's canvas as RGBA bytes, drawn first if a frame is waiting.
function picture(view) {
  if (state.dirty) draw();
  const c = canvases[view], copy = document.createElement('canvas');
  copy.width = c.width;
  copy.height = c.height;
  const ctx = copy.getContext('2d');
  ctx.drawImage(c, 0, 0);
  return ctx.getImageData(0, 0, c.width, c.height).data;
}

// For the browser test: the state, the journal, the views' positions and pixels.
// The two evaluators at the current frame: the largest difference of GPU (read back through
// transform feedback) and CPU positions over both views, the model's size, the largest
// displacement.
function compareEvaluators() {
  const n = 3 * M._mbi_vertex_count(), rest = floats(M._mbi_rest_positions(), n).slice();  // wasm may grow
  let worst = 0, size = 0, moved = 0;
  views.forEach((v, k) => {
    const g = v.gpu.positions(rest), c = positions(k);
    for (let i = 0; i < n; ++i) {
      worst = Math.max(worst, Math.abs(g[i] - c[i]));
      size = Math.max(size, Math.abs(c[i]));
      moved = Math.max(moved, Math.abs(c[i] - rest[i]));
    }
  });
  return { worst, size, moved, points: n / 3 };
}

// The modified-BI view's evaluation at the current frame, `repeats` times each, in ms: the GPU
// pass (upload of the Bezier texels, pass, waiting for it) and the wasm CPU path.
function benchEvaluators(repeats) {
  const v = views[1], rows = M._mbi_bezier_rows(), texels = floats(M._mbi_bezier_texels(1), 4 * rows);
  const mean = (f) => {
    f();  // one untimed
    const t0 = performance.now();
    for (let r = 0; r < repeats; ++r) f();
    return (performance.now() - t0) / repeats;
  };
  const gpu = mean(() => { v.gpu.evaluate(texels); v.gpu.read(3); });
  let inWasm = 0;  // the evaluation alone, without the Bezier points and the copy to floats
  const cpu = mean(() => { inWasm += M._mbi_evaluate_cpu(1); });
  return { gpu, cpu, wasm: inWasm / (repeats + 1), points: M._mbi_vertex_count(), renderer: v.renderer() };
}

window.mbiPage = {
  drawPath, journal, state, api, scenes, gpuAvailable, gpuProblem, compareEvaluators, benchEvaluators,
  evaluator: () => (state.gpu ? 'gpu' : 'cpu'),
  setEvaluator: (name) => setEvaluator(name === 'gpu'),
  setCreases: (on) => { $('creases').checked = on; state.creases = on; frameChanged(); },
  setColliders: (on) => { $('colliders').checked = on; state.colliders = on; state.dirty = true; },
  note: () => note,
  status: () => status(),
  renderer: drawPath === 'WebGL2' ? views[0].renderer() : '',
  benchSolve: (repeats) => M._mbi_bench_solve(repeats),
  positions: (view) => Array.from(positions(view)),
  triangles: () => Array.from(triangles()),
  // where a model point appears in a view's canvas (CSS pixels from the page's corner)
  screenOf(view, p) {
    const c = canvases[view], r = c.getBoundingClientRect(), m = state.camera.matrix(c.width, c.height);
    const w = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
    const x = ((m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12]) / w + 1) / 2;
    const y = (1 - (m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13]) / w) / 2;
    return [r.left + x * r.width, r.top + y * r.height];
  },
  table: () => state.table,
  // a view's picture as grey levels (0-255), one per pixel
  pixels(view) {
    const d = picture(view), g = new Uint8Array(d.length / 4);
    for (let i = 0; i < g.length; ++i) g[i] = (d[4 * i] + d[4 * i + 1] + d[4 * i + 2]) / 3;
    return Array.from(g);
  },
  // a view's picture: the mean of red minus blue (0-255) over the model's pixels (not the
  // near-white background), and how many there are
  pictureHeat(view) {
    const d = picture(view);
    let sum = 0, n = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (d[i] > 235 && d[i + 1] > 235 && d[i + 2] > 235) continue;
      sum += d[i] - d[i + 2];
      ++n;
    }
    return { heat: n ? sum / n : 0, pixels: n };
  },
};

setPlaying(state.playing);
$('evaluator').querySelector('[value=gpu]').disabled = !gpuAvailable;
state.gpu = gpuAvailable && params.get('eval') !== 'cpu';
$('evaluator').value = state.gpu ? 'gpu' : 'cpu';
// ?scene=<name> picks the scene (else the twisting bar, else the first the page runs)
const named = (name) => scenes.findIndex((s) => s.name === name && !s.problem);
const first = [params.get('scene'), 'twist-bar'].map(named).find((k) => k >= 0);
loadScene(first ?? scenes.findIndex((s) => !s.problem));
requestAnimationFrame(loop);
