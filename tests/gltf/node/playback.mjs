// node playback.mjs ANIM.glb CACHE.pc2 INPUT.glb
// Reads an animated glTF of mbi with three.js's GLTFLoader and plays its animation: at each
// frame's time exactly that frame's node is shown (scale 1, the others 0), and the positions
// three.js reads for it equal the point cache's frame (float round-off); every part keeps the
// material and UVs of the input asset. Exit 1 on the first difference.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { readFileSync } from 'node:fs';

const [animFile, cacheFile, inputFile] = process.argv.slice(2);
if (!inputFile) throw new Error('usage: node playback.mjs ANIM.glb CACHE.pc2 INPUT.glb');

const load = (file) => new Promise((resolve, reject) => {
  const b = readFileSync(file);
  new GLTFLoader().parse(b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength), '', resolve, reject);
});
const fail = (what) => { console.error(`${animFile}: ${what}`); process.exit(1); };
const meshesOf = (object) => { const m = []; object.traverse((o) => { if (o.isMesh) m.push(o); }); return m; };

// PC2: "POINTCACHE2\0", version, points, start frame, sample rate, samples; then float32 x y z.
function readPc2(file) {
  const b = readFileSync(file);
  const points = b.readInt32LE(16), samples = b.readInt32LE(28);
  const frames = [];
  for (let k = 0; k < samples; ++k)
    frames.push(new Float32Array(b.buffer.slice(b.byteOffset + 32 + k * points * 12, b.byteOffset + 32 + (k + 1) * points * 12)));
  return frames;
}

const anim = await load(animFile), input = await load(inputFile);
const cache = readPc2(cacheFile);
const frames = anim.scene.children[0].children;
if (frames.length !== cache.length) fail(`${frames.length} frame nodes, the cache has ${cache.length} frames`);

// positions of each frame against the cache
let extent = 0;
for (const x of cache[0]) extent = Math.max(extent, Math.abs(x));
for (let k = 0; k < frames.length; ++k) {
  const got = meshesOf(frames[k]).flatMap((m) => Array.from(m.geometry.attributes.position.array));
  if (got.length !== cache[k].length) fail(`frame ${k}: ${got.length / 3} positions, the cache has ${cache[k].length / 3}`);
  let worst = 0;
  for (let i = 0; i < got.length; ++i) worst = Math.max(worst, Math.abs(got[i] - cache[k][i]));
  if (worst > 1e-5 * extent) fail(`frame ${k}: positions differ from the cache by ${worst}`);
}

// playback: at frame k's time, node k alone is shown
const clip = anim.animations[0];
if (!clip) fail('no animation');
const mixer = new THREE.AnimationMixer(anim.scene);
mixer.clipAction(clip).play();
for (let k = 0; k < frames.length; ++k) {
  const track = clip.tracks.find((t) => t.name === `${frames[k].name}.scale`);
  if (!track) fail(`no scale track for ${frames[k].name}`);
  mixer.setTime(track.times[k === 0 ? 0 : 1]);
  frames.forEach((f, i) => {
    if (f.scale.x !== (i === k ? 1 : 0)) fail(`at frame ${k}'s time node ${f.name} has scale ${f.scale.x}`);
  });
}

// every part keeps the input's material and UVs
const parts = meshesOf(input.scene), ours = meshesOf(frames[0]);
if (parts.length !== ours.length) fail(`${ours.length} parts, the input has ${parts.length}`);
parts.forEach((p, i) => {
  const q = ours[i];
  if (q.material.name !== p.material.name || !q.material.color.equals(p.material.color))
    fail(`part ${i}: material ${q.material.name}, the input's is ${p.material.name}`);
  const a = p.geometry.attributes.uv.array, b = q.geometry.attributes.uv?.array;
  if (!b || a.length !== b.length || a.some((x, j) => x !== b[j])) fail(`part ${i}: UVs differ from the input's`);
});
console.log(`${animFile}: ${frames.length} frames, ${ours.length} parts: positions, playback, materials and UVs as expected`);
