// node obj_corners.mjs ANIM.glb MODEL.obj CACHE.pc2 MATERIALS.json
// Reads an animated glTF that mbi wrote from an OBJ with three.js's GLTFLoader and checks it
// against the OBJ, corner by corner: the primitives are the OBJ's (group, material) runs in order
// of first appearance, their triangles its faces fan-triangulated in file order; every corner's
// UV is the OBJ's (u, 1 - v) within 1e-7, its position at every frame the point cache's position
// of the OBJ vertex (float32 round-off); each primitive's material is the one MATERIALS.json
// names ({"name": {"color": [r, g, b], "opacity": a, "map": image URI, "stored" (in the file) or null}}). Exit 1 on the first difference.
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { readFileSync } from 'node:fs';

const [animFile, objFile, cacheFile, materialsFile] = process.argv.slice(2);
if (!materialsFile) throw new Error('usage: node obj_corners.mjs ANIM.glb MODEL.obj CACHE.pc2 MATERIALS.json');
const fail = (what) => { console.error(`${animFile}: ${what}`); process.exit(1); };

// three.js's loader refers to `self` for image URLs; in node no image loads and the material
// keeps no map (the texture is checked in the file's JSON below)
globalThis.self ??= globalThis;
const b = readFileSync(animFile);
const anim = await new Promise((resolve, reject) =>
  new GLTFLoader().parse(b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength), '', resolve, reject));

// the OBJ: vt, faces (v, vt per corner, 0-based) grouped by (g or o, usemtl) in order of first appearance
const vt = [], parts = new Map();
let group = '', material = '';
for (const line of readFileSync(objFile, 'utf8').split('\n')) {
  const w = line.trim().split(/\s+/);
  if (w[0] === 'vt') vt.push([Number(w[1]), Number(w[2])]);
  else if (w[0] === 'g' || w[0] === 'o') group = w.slice(1).join(' ');
  else if (w[0] === 'usemtl') material = w.slice(1).join(' ');
  else if (w[0] === 'f') {
    const key = `${group}\u0000${material}`;
    if (!parts.has(key)) parts.set(key, { material, faces: [] });
    parts.get(key).faces.push(w.slice(1).map((c) => c.split('/').map((x) => Number(x) - 1)));
  }
}

// PC2: "POINTCACHE2\0", version, points, start frame, sample rate, samples; then float32 x y z
const c = readFileSync(cacheFile);
const points = c.readInt32LE(16), samples = c.readInt32LE(28);
const cache = (k, v, d) => c.readFloatLE(32 + ((k * points + v) * 3 + d) * 4);

const materials = JSON.parse(readFileSync(materialsFile, 'utf8'));
const frames = anim.scene.children[0].children;
if (frames.length !== samples) fail(`${frames.length} frame nodes, the cache has ${samples} frames`);
let corners = 0;
frames.forEach((frame, k) => {
  const meshes = [];
  frame.traverse((o) => { if (o.isMesh) meshes.push(o); });
  if (meshes.length !== parts.size) fail(`frame ${k}: ${meshes.length} primitives, the OBJ has ${parts.size} groups/materials`);
  [...parts.values()].forEach((part, p) => {
    const g = meshes[p].geometry, index = g.index.array, pos = g.attributes.position.array, uv = g.attributes.uv?.array;
    if (!uv) fail(`frame ${k}: primitive ${p}: no UVs`);
    let t = 0;
    for (const f of part.faces)
      for (let j = 1; j + 1 < f.length; ++j, ++t)
        [f[0], f[j], f[j + 1]].forEach(([v, tex], corner) => {
          const i = index[3 * t + corner];
          for (let d = 0; d < 3; ++d) {
            const want = cache(k, v, d);
            if (Math.abs(pos[3 * i + d] - want) > 1e-6 * Math.max(1, Math.abs(want)))
              fail(`frame ${k}: primitive ${p}: triangle ${t} corner ${corner}: position ${pos[3 * i + d]}, the cache has ${want}`);
          }
          const [u, w] = vt[tex];
          if (Math.abs(uv[2 * i] - u) > 1e-7 || Math.abs(uv[2 * i + 1] - (1 - w)) > 1e-7)
            fail(`frame ${k}: primitive ${p}: triangle ${t} corner ${corner}: UV (${uv[2 * i]}, ${uv[2 * i + 1]}), the OBJ's is (${u}, ${1 - w}) in glTF's v`);
          ++corners;
        });
    if (3 * t !== index.length) fail(`frame ${k}: primitive ${p}: ${index.length / 3} triangles, the OBJ has ${t}`);
    const m = meshes[p].material, want = materials[part.material];
    if (m.name !== part.material || !want) fail(`primitive ${p}: material '${m.name}', the OBJ's is '${part.material}'`);
    if (want.color.some((x, d) => Math.abs(x - [m.color.r, m.color.g, m.color.b][d]) > 1e-6))
      fail(`material ${m.name}: colour ${m.color.toArray()}, the MTL's Kd is ${want.color}`);
    if (Math.abs(m.opacity - want.opacity) > 1e-6 || m.transparent !== want.opacity < 1)
      fail(`material ${m.name}: opacity ${m.opacity} (transparent ${m.transparent}), the MTL's is ${want.opacity}`);
    // the texture as the file names it (three.js in node loads no image)
    const json = anim.parser.json, jm = json.materials.find((x) => x.name === m.name);
    const tex = jm?.pbrMetallicRoughness?.baseColorTexture;
    const image = tex ? json.images[json.textures[tex.index].source] : null;
    const uri = image ? image.uri ?? (image.bufferView !== undefined ? 'stored' : undefined) : null;
    if (uri !== want.map) fail(`material ${m.name}: texture ${uri}, expected ${want.map}`);
  });
});
console.log(`${animFile}: ${frames.length} frames, ${parts.size} primitives, ${corners} corners: UVs, positions and materials as the OBJ's`);
