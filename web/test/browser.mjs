// The page in a real browser: headless Chromium (Debian's, driven by playwright-core) loads the
// built page from a local http server, pokes the twisting bar (scenes/twist-bar.toml) with
// scripted mouse events and checks that
//   - the page's scene list is scenes/*.toml, those it cannot run greyed with the reason (the
//     scenes that drag handles by keyframes, and those with a mesh collider, the key named);
//   - the picture changes where the poked bar moves;
//   - BI creases and modified-BI does not (the largest change of a dihedral angle between
//     neighbouring dense triangles, against the rest shape, is several times larger for BI), the
//     page's discontinuity table says so, and the picture in crease colours shows it (BI's view
//     hotter);
//   - the page's positions equal the native build's for the same calls (the page's journal
//     replayed by mbi-web-twin) to float round-off, its discontinuity table the native one's: on
//     the poked bar, and on every other scene the page runs after a few frames;
//   - the other draw path draws too (the 2D canvas fallback when WebGL2 ran);
//   - an OBJ file given to the page loads in a control mesh generated there, and runs;
//   - contact at the dense surface: a scene file given to the page (tests/data/scenes/
//     page-contact.toml: a sphere, a capsule, a box, a ground plane) runs the module's contact,
//     its positions and touching count the native build's after 12 frames (which equal `mbi
//     run`'s: tests/web's test_page_scenes), the count shown (> 0), the colliders drawn; a scene
//     with a mesh collider (scenes/steps.toml) given to the page is refused, naming the key;
//   - with WebGL2: the GPU evaluator (transform feedback, read back) gives the CPU's positions
//     to float round-off on the bar and on scenes/large.toml's sphere of 252,152 points, poked; the
//     switch to the CPU evaluator works.
// It says which draw path and which evaluator ran (and when WebGL2 is missing). Usage:
//   node browser.mjs --page <build/web/page> --twin <mbi-web-twin> [--out <dir>] [--bench]
// --bench adds the numbers of the bench report (wasm ms per frame, fps, solve at 448, the two
// evaluators on 252K points).
import { chromium } from 'playwright-core';
import { execFileSync } from 'node:child_process';
import { createServer } from 'node:http';
import { mkdtempSync, readFileSync, readdirSync, writeFileSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, extname, basename } from 'node:path';
import { fileURLToPath } from 'node:url';

const arg = (name, fallback) => {
  const i = process.argv.indexOf('--' + name);
  return i > 0 ? process.argv[i + 1] : fallback;
};
const pageDir = arg('page'), twin = arg('twin'), out = arg('out', mkdtempSync(join(tmpdir(), 'mbi-web-')));
const bench = process.argv.includes('--bench');
let failures = 0;
const check = (ok, what) => {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures++;
};

// A static file server for the built page.
const types = { '.html': 'text/html', '.js': 'text/javascript', '.wasm': 'application/wasm', '.css': 'text/css' };
function serve(dir) {
  const server = createServer((req, res) => {
    const file = join(dir, decodeURIComponent(new URL(req.url, 'http://x').pathname));
    if (!file.startsWith(dir) || !existsSync(file)) return res.writeHead(404).end();
    res.writeHead(200, { 'content-type': types[extname(file)] || 'application/octet-stream' });
    res.end(readFileSync(file));
  });
  return new Promise((ok) => server.listen(0, '127.0.0.1', () => ok(server)));
}

async function open(browser, url) {
  const page = await browser.newPage({ viewport: { width: 1200, height: 900 } });
  page.on('pageerror', (e) => check(false, 'page error: ' + e.message));
  const wasm = [];
  page.on('request', (r) => { if (r.url().endsWith('.wasm')) wasm.push(r.url()); });
  await page.goto(url);
  await page.waitForFunction(() => window.mbiPage !== undefined, null, { timeout: 30000 });
  check(wasm.length === 1, `one instance of the module (main.js and camera.js share it): ${wasm.length} .wasm fetches`);
  return page;
}

// Largest change of the angle between neighbouring triangles' normals from `rest` to `now`, over
// the edges that are smooth at rest (the bar's own edges, 90 degrees, are left out).
function creaseChange(triangles, rest, now) {
  const normal = (p, f) => {
    const v = (k) => [0, 1, 2].map((c) => p[3 * triangles[3 * f + k] + c]);
    const a = v(0), b = v(1), c = v(2);
    const e = [b[0] - a[0], b[1] - a[1], b[2] - a[2]], g = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    const n = [e[1] * g[2] - e[2] * g[1], e[2] * g[0] - e[0] * g[2], e[0] * g[1] - e[1] * g[0]];
    const l = Math.hypot(...n);
    return n.map((x) => x / l);
  };
  const angle = (p, f, g) => {
    const a = normal(p, f), b = normal(p, g);
    return Math.acos(Math.max(-1, Math.min(1, a[0] * b[0] + a[1] * b[1] + a[2] * b[2])));
  };
  const edges = new Map();
  let worst = 0;
  for (let f = 0; f < triangles.length / 3; ++f)
    for (let k = 0; k < 3; ++k) {
      const i = triangles[3 * f + k], j = triangles[3 * f + (k + 1) % 3];
      const key = Math.min(i, j) * 1e7 + Math.max(i, j);
      if (!edges.has(key)) { edges.set(key, f); continue; }
      const g = edges.get(key), before = angle(rest, f, g);
      if (before < 0.35) worst = Math.max(worst, Math.abs(angle(now, f, g) - before));  // not the box's edges
    }
  return worst * 180 / Math.PI;
}

const changed = (a, b) => a.filter((x, i) => Math.abs(x - b[i]) > 24).length / a.length;

// The poke: press on the bar's axis at 3/4 of its length (the ray there meets its surface),
// drag sideways, step with the keyboard while holding, release.
async function poke(page, view, frames) {
  const [x, y] = await page.evaluate((v) => mbiPage.screenOf(v, [0, 0, 4.5]), view);
  await page.mouse.move(x, y);
  await page.mouse.down();
  await page.mouse.move(x + 90, y - 20, { steps: 6 });
  for (let k = 0; k < frames; ++k) await page.keyboard.press('s');
  await page.mouse.up();
  return page.evaluate(() => mbiPage.journal.includes('release'));
}

async function main() {
  const server = await serve(pageDir);
  const base = `http://127.0.0.1:${server.address().port}/index.html`;
  const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', args: ['--no-sandbox'] });
  try {
    const page = await open(browser, base + '?scene=twist-bar&play=0');
    const runs = await sceneList(page);
    const path = await page.evaluate(() => mbiPage.drawPath);
    const renderer = await page.evaluate(() => mbiPage.renderer);
    console.log(`draw path: ${path}${renderer ? ' (' + renderer + ')' : ''}`);
    const gpu = await page.evaluate(() => [mbiPage.gpuAvailable, mbiPage.gpuProblem, mbiPage.evaluator()]);
    console.log(gpu[0] ? `evaluator: ${gpu[2]} (the GPU pass builds: WebGL2 transform feedback)`
      : `evaluator: ${gpu[2]}; the GPU pass is unavailable (${gpu[1]}): GPU == CPU is not checked`);
    const triangles = await page.evaluate(() => mbiPage.triangles());
    const rest = await page.evaluate(() => mbiPage.positions(1));
    const heatOf = () => page.evaluate(() => [mbiPage.pictureHeat(0), mbiPage.pictureHeat(1)]);
    await page.evaluate(() => mbiPage.setCreases(true));
    const cold = await heatOf();  // at rest nothing glows
    await page.evaluate(() => mbiPage.setCreases(false));
    for (let k = 0; k < 30; ++k) await page.keyboard.press('s');  // 30 degrees of twist
    const before = await page.evaluate(() => mbiPage.pixels(1));
    const twisted = [0, 1].map(() => null);
    twisted[0] = await page.evaluate(() => mbiPage.positions(0));
    twisted[1] = await page.evaluate(() => mbiPage.positions(1));
    const creaseBI = creaseChange(triangles, rest, twisted[0]), creaseMBI = creaseChange(triangles, rest, twisted[1]);
    check(creaseBI > 3 * creaseMBI, `creases after 30 degrees of twist: BI ${creaseBI.toFixed(2)} deg, ` +
          `modified-BI ${creaseMBI.toFixed(2)} deg (BI at least 3 times larger)`);
    if (gpu[0]) await gpuChecks(page, 'the twisting bar');
    // the picture in crease colours (which replace the views' tints) warms from the rest shape's
    // where the discontinuity table says the method creases: BI's, and far less modified-BI's
    const t = await page.evaluate(() => mbiPage.table());
    check(t && t.bi > 10 * t.modifiedBi, `the discontinuity table after 30 degrees: mean E_F BI ` +
          `${t?.bi.toExponential(2)}, modified-BI ${t?.modifiedBi.toExponential(2)} (BI at least 10 times larger)`);
    await page.evaluate(() => mbiPage.setCreases(true));
    const heat = await heatOf(), warmed = heat.map((h, k) => h.heat - cold[k].heat);
    await page.screenshot({ path: join(out, 'web-creases.png') });
    check(heat.every((h) => h.pixels > 5000) && warmed[0] > 20 && Math.abs(warmed[1]) < warmed[0] / 3,
          `the picture in crease colours (mean red minus blue of the model's pixels, 0-255), rest -> ` +
          `30 degrees: BI ${cold[0].heat.toFixed(1)} -> ${heat[0].heat.toFixed(1)}, modified-BI ` +
          `${cold[1].heat.toFixed(1)} -> ${heat[1].heat.toFixed(1)} (BI warms by 20 or more, modified-BI by a third of that at most)`);
    await page.evaluate(() => mbiPage.setCreases(false));

    check(await poke(page, 1, 15), 'a scripted mouse drag poked the bar (grab, move, release)');
    const after = await page.evaluate(() => mbiPage.pixels(1));
    const moved = changed(before, after);
    check(moved > 0.005, `the poked bar moved: ${(100 * moved).toFixed(2)} % of the modified-BI view changed`);
    await page.screenshot({ path: join(out, 'web-page.png'), fullPage: true });

    await againstTwin(page, 'twist-bar');
    if (bench) await measure(page);
    if (gpu[0]) {
      await page.selectOption('#evaluator', 'cpu');
      const cpu = await page.evaluate(() => [mbiPage.evaluator(), mbiPage.status()]);
      check(cpu[0] === 'cpu' && cpu[1].includes('evaluation: CPU (wasm)'), 'the switch to the CPU evaluator: the page says so');
    }
    await page.close();
    if (gpu[0]) await dense(browser, base);

    // the other path: the 2D canvas fallback (when WebGL2 ran above)
    if (path === 'WebGL2') {
      const flat = await open(browser, base + '?scene=twist-bar&play=0&draw=2d');
      const seen = await flat.evaluate(() => [mbiPage.drawPath, mbiPage.pixels(1), mbiPage.evaluator(), mbiPage.status()]);
      const drawn = seen[1].filter((g) => g < 200).length / seen[1].length;
      check(seen[0] === '2D canvas' && drawn > 0.02,
            `the 2D canvas fallback draws the bar (${(100 * drawn).toFixed(1)} % of its view)`);
      check(seen[2] === 'cpu' && seen[3].includes('evaluation: CPU (wasm): the GPU pass is unavailable (no WebGL2)'),
            'without WebGL2 the page evaluates on the CPU and says why');
      await flat.close();
    }

    // a user's OBJ: read in the page, its control mesh generated there
    const own = await open(browser, base + '?scene=poke&play=0');
    await own.setInputFiles('#file', fileURLToPath(new URL('../../tests/data/vtu/sphere.obj', import.meta.url)));
    await own.waitForFunction(() => mbiPage.api.description().startsWith('your model'), null, { timeout: 30000 });
    for (let k = 0; k < 3; ++k) await own.keyboard.press('s');
    const loadedObj = await own.evaluate(() => [mbiPage.api.description(), mbiPage.state.frame]);
    check(loadedObj[1] === 3, `an OBJ given to the page runs: ${loadedObj[0]}, frame ${loadedObj[1]}`);
    await own.close();

    await contact(browser, base);

    // every other scene the page runs, a few frames on, against the native build
    for (const name of runs.filter((s) => s !== 'twist-bar')) {
      const p = await open(browser, `${base}?scene=${name}&play=0`);
      const said = await p.evaluate(() => [mbiPage.api.description(), mbiPage.api.error()]);
      check(said[0].startsWith(name + ':'), `the page loads scenes/${name}.toml: ${said[0] || said[1]}`);
      for (let k = 0; k < 5; ++k) await p.keyboard.press('s');
      await againstTwin(p, name);
      await p.close();
    }
  } finally {
    await browser.close();
    server.close();
  }
  console.log(failures ? `${failures} check(s) failed` : `all checks passed (draw path above; files in ${out})`);
  process.exit(failures ? 1 : 0);
}

// The page's scene list against scenes/*.toml: every file listed by its name; greyed with a
// reason exactly for the scenes that drag handles by keyframes (the page pokes simulations) and
// those with a mesh collider (no OpenVDB in the page; the reason names the collider's key).
// The names of the scenes the page runs.
async function sceneList(page) {
  const folder = fileURLToPath(new URL('../../scenes/', import.meta.url));
  const files = readdirSync(folder).filter((f) => f.endsWith('.toml')).sort();
  const listed = await page.evaluate(() => mbiPage.scenes);
  const options = await page.evaluate(() => Array.from(document.querySelectorAll('#scene option'), (o) => [o.text, o.disabled]));
  check(listed.map((s) => s.name).join() === files.map((f) => basename(f, '.toml')).join(),
        `the page lists the scene files of scenes/: ${listed.map((s) => s.name).join(', ')}`);
  for (const [k, f] of files.entries()) {
    const text = readFileSync(join(folder, f), 'utf8');
    const drags = /^mode\s*=\s*"drag"/m.test(text), mesh = /^shape\s*=\s*"mesh"/m.test(text), refused = drags || mesh;
    const s = listed[k] || { name: f, problem: '' };
    const named = !mesh || (/colliders\[\d+\]\.shape = "mesh"/.test(s.problem) && s.problem.includes('OpenVDB'));
    check(refused === (s.problem !== '') && options[k]?.[1] === refused && (!refused || options[k][0].includes(s.problem)) && named,
          `scenes/${f}: ${refused ? 'greyed: ' + s.problem : 'the page runs it'}`);
  }
  return listed.filter((s) => !s.problem).map((s) => s.name);
}

// The page's journal replayed in the native build (mbi-web-twin; the scene files given to the
// page read from `folder`): both views' positions equal to float round-off, the discontinuity
// table to 1e-9 (both compute it in double), the touching points equal.
async function againstTwin(page, what, folder = '.') {
  const journal = await page.evaluate(() => mbiPage.journal.join('\n') + '\n');
  writeFileSync(join(out, `journal-${what}.txt`), journal);
  const said = execFileSync(twin, ['replay', join(out, `journal-${what}.txt`), join(out, `native-${what}.bin`), folder],
                            { encoding: 'utf8', stdio: ['ignore', 'pipe', 'inherit'] });
  process.stdout.write(said);
  const bytes = readFileSync(join(out, `native-${what}.bin`));
  const native = new Float32Array(bytes.buffer, bytes.byteOffset, bytes.length / 4);
  const page0 = await page.evaluate(() => mbiPage.positions(0)), page1 = await page.evaluate(() => mbiPage.positions(1));
  const n = page0.length;
  let worst = 0, size = 0;
  for (let i = 0; i < n; ++i) {
    worst = Math.max(worst, Math.abs(page0[i] - native[i]), Math.abs(page1[i] - native[n + i]));
    size = Math.max(size, Math.abs(native[i]));
  }
  check(native.length === 2 * n && worst <= 1e-5 * size,
        `${what}: page vs native positions after ${journal.split('\n').length - 1} calls: largest difference ` +
        `${worst.toExponential(2)} m (model size ${size.toFixed(1)} m; float round-off allowed: 1e-5 of it)`);
  // contact's Newton stops at a tolerance: the builds' round-off reaches the positions (1e-6 m
  // measured), and E_F, a sum of squared jumps, far more than in double alone
  const contact = await page.evaluate(() => mbiPage.api.colliders() > 0), relative = contact ? 1e-4 : 1e-9;
  const m = said.match(/table: BI mean (\S+) modified-BI mean (\S+)/), tp = await page.evaluate(() => mbiPage.table());
  const close = (a, b) => Math.abs(a - b) <= relative * Math.abs(b);
  check(m && tp && close(tp.bi, Number(m[1])) && close(tp.modifiedBi, Number(m[2])),
        `${what}: page vs native discontinuity table: BI ${tp?.bi.toExponential(6)} vs ${m && Number(m[1]).toExponential(6)}, ` +
        `modified-BI ${tp?.modifiedBi.toExponential(6)} vs ${m && Number(m[2]).toExponential(6)} (relative ${relative})`);
  const touching = Number(said.match(/touching: (\d+)/)?.[1]), shown = await page.evaluate(() => mbiPage.api.touching());
  check(touching === shown, `${what}: page vs native touching points: ${shown} vs ${touching}`);
}

// Contact at the dense surface: a scene file with colliders given to the page runs as natively
// and as `mbi run` (positions, touching count), its colliders drawn; a mesh collider refused.
async function contact(browser, base) {
  const data = fileURLToPath(new URL('../../tests/data/scenes/', import.meta.url));
  const page = await open(browser, base + '?scene=poke&play=0');
  await page.setInputFiles('#file', join(data, 'page-contact.toml'));
  await page.waitForFunction(() => mbiPage.api.description().startsWith('page-contact:'), null, { timeout: 30000 });
  for (let k = 0; k < 12; ++k) await page.keyboard.press('s');
  const [frame, touching, status] = await page.evaluate(() => [mbiPage.state.frame, mbiPage.api.touching(), mbiPage.status()]);
  const line = status.split('\n').find((l) => l.startsWith('contact at the dense surface')) || '(no contact line)';
  check(frame === 12 && touching > 0 && line.includes(`${touching} dense vertices touching, 4 colliders`),
        `page-contact.toml given to the page, frame ${frame}: the status says "${line}" (touching > 0)`);
  await againstTwin(page, 'page-contact', data);
  const drawn = await page.evaluate(() => mbiPage.pixels(1));
  await page.screenshot({ path: join(out, 'web-contact.png') });
  await page.evaluate(() => mbiPage.setColliders(false));
  const hidden = await page.evaluate(() => mbiPage.pixels(1));
  const share = changed(drawn, hidden);
  check(share > 0.02, `the colliders are drawn: hiding them changes ${(100 * share).toFixed(1)} % of the modified-BI view`);

  const scenes = fileURLToPath(new URL('../../scenes/', import.meta.url));
  await page.setInputFiles('#file', join(scenes, 'steps.toml'));
  await page.waitForFunction(() => mbiPage.note() !== '', null, { timeout: 30000 });
  const refusal = await page.evaluate(() => [mbiPage.note(), mbiPage.api.description()]);
  check(/steps\.toml: the page cannot run this scene: colliders\[0\]\.shape = "mesh"/.test(refusal[0]) &&
        refusal[0].includes('OpenVDB') && refusal[1].startsWith('page-contact:'),
        `scenes/steps.toml (a mesh collider) given to the page is refused, the scene before kept: "${refusal[0]}"`);
  await page.close();
}

// GPU == CPU at the current frame (both views), the GPU's positions read back from the
// transform feedback buffer.
async function gpuChecks(page, what) {
  const c = await page.evaluate(() => mbiPage.compareEvaluators());
  check(c.worst <= 1e-5 * c.size && c.moved > 1e-3 * c.size,
        `GPU == CPU on ${what} (${c.points} points, both views, moved up to ${c.moved.toFixed(3)}): largest ` +
        `difference ${c.worst.toExponential(2)} (model size ${c.size.toFixed(2)}; float round-off allowed: 1e-5 of it)`);
}

// The bumpy sphere of 252,152 points (scenes/large.toml), poked through the API (a ray down the z
// axis) for a few frames on the GPU: GPU == CPU, and the two evaluators side by side.
async function dense(browser, base) {
  const t0 = Date.now();
  const page = await open(browser, base + '?scene=large&play=0');
  await page.waitForFunction(() => mbiPage.api.description().startsWith('large:'), null, { timeout: 60000 });
  const hit = await page.evaluate(() => mbiPage.api.grab(1, 0, 0, 5, 0, 0, -1) === 1 &&
                                        (mbiPage.api.move(0.6, 0.4, 5, 0, 0, -1), true));
  for (let k = 0; k < 4; ++k) await page.keyboard.press('s');
  check(hit && (await page.evaluate(() => mbiPage.evaluator())) === 'gpu', 'the large scene\'s sphere poked, on the GPU evaluator');
  await gpuChecks(page, 'the large scene\'s sphere');
  const b = await page.evaluate((n) => mbiPage.benchEvaluators(n), bench ? 20 : 3);
  const f = (x) => x.toFixed(2);
  console.log(`${bench ? 'bench' : 'evaluators'}: ${b.points} points, modified-BI view, ms per evaluation: GPU pass ` +
              `${f(b.gpu)} (upload, pass, wait; ${b.renderer}), wasm CPU ${f(b.cpu)} (of which the evaluation ` +
              `${f(b.wasm)}); mean of ${bench ? 20 : 3}`);
  await page.close();
  console.log(`(the large scene's checks took ${((Date.now() - t0) / 1000).toFixed(1)} s)`);
}

// The bench report's numbers: the bar playing for 120 frames on the CPU evaluator (wasm ms per
// phase, fps), the solve at 448 control vertices.
async function measure(page) {
  await page.evaluate(() => mbiPage.setEvaluator('cpu'));  // the wasm phases, evaluation included
  await page.keyboard.press('r');
  await page.keyboard.press(' ');
  await page.waitForFunction(() => mbiPage.state.frame >= 120, null, { timeout: 120000, polling: 100 });
  await page.keyboard.press(' ');
  const r = await page.evaluate(() => ({ fps: mbiPage.state.fps, wasm: mbiPage.state.wasm,
                                          sums: mbiPage.state.sums, steps: mbiPage.state.steps }));
  const mean = r.wasm.reduce((a, b) => a + b, 0) / r.wasm.length;
  const p = r.sums.map((x) => x / r.steps), f = (x) => x.toFixed(3);
  console.log(`bench: twisting bar, ${r.steps} frames in wasm, ms per frame: simulation ${f(p[0])}, solve ` +
              `${f(p[1])}, Bezier ${f(p[2])}, evaluation ${f(p[3])}: ${f(p[0] + p[1] + p[2] + p[3])} in all; the ` +
              `other view ${f(p[4])}; a whole step seen from script ${f(mean)} (last ${r.wasm.length} frames)`);
  console.log(`bench: headless Chromium (software rendering) ${r.fps.toFixed(1)} fps`);
  const solve = await page.evaluate(() => mbiPage.benchSolve(200));
  console.log(`bench: wasm modified-BI solve at 448 control vertices ${solve.toFixed(4)} ms`);
}

main().catch((e) => { console.error(e); process.exit(1); });
