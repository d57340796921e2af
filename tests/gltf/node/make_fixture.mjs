// Writes the multi-part fixture with three.js's GLTFExporter (a writer we did not write):
//   node make_fixture.mjs OUT.glb
// A body with a head (a child node, scaled), two wheels sharing one mesh (instances), each part
// with its own material; every geometry has normals and UVs.
import * as THREE from 'three';
import { GLTFExporter } from 'three/addons/exporters/GLTFExporter.js';
import { writeFileSync } from 'node:fs';

// GLTFExporter reads its Blob back through FileReader, which node lacks.
globalThis.FileReader = class {
  readAsArrayBuffer(blob) {
    blob.arrayBuffer().then((b) => { this.result = b; this.onloadend?.(); });
  }
  readAsDataURL(blob) {
    blob.arrayBuffer().then((b) => {
      this.result = `data:${blob.type || 'application/octet-stream'};base64,${Buffer.from(b).toString('base64')}`;
      this.onloadend?.();
    });
  }
};

const material = (name, color) => {
  const m = new THREE.MeshStandardMaterial({ color, roughness: 0.6, metalness: 0.1 });
  m.name = name;
  return m;
};

const scene = new THREE.Scene();
const root = new THREE.Group();
root.name = 'toy';
root.position.set(0.5, 0.2, -0.3);
root.rotation.set(0, Math.PI / 6, 0);
scene.add(root);

const body = new THREE.Mesh(new THREE.BoxGeometry(2, 0.8, 1, 4, 2, 2), material('paint', 0xcc3322));
body.name = 'body';
root.add(body);

const head = new THREE.Mesh(new THREE.SphereGeometry(0.35, 12, 8), material('glass', 0x3366cc));
head.name = 'head';
head.position.set(0.4, 0.7, 0);
head.scale.set(1.2, 1, 1.2);
body.add(head);

const wheelGeometry = new THREE.CylinderGeometry(0.3, 0.3, 0.2, 12);
const rubber = material('rubber', 0x222222);
for (const [i, x] of [[0, -0.6], [1, 0.6]]) {
  const wheel = new THREE.Mesh(wheelGeometry, rubber);
  wheel.name = `wheel_${i}`;
  wheel.position.set(x, -0.45, 0.55);
  wheel.rotation.set(Math.PI / 2, 0, 0);
  root.add(wheel);
}

const out = process.argv[2];
if (!out) throw new Error('usage: node make_fixture.mjs OUT.glb');
new GLTFExporter().parse(scene, (glb) => writeFileSync(out, Buffer.from(glb)),
  (e) => { throw e; }, { binary: true });
