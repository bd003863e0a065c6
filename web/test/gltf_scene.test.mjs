// SPDX-License-Identifier: MIT
// PMZGLTFPlugin on a scene GLB in headless Chromium: pmz-encode keeps the scene of
// tests/tools/make_scene_gltf.py (meshes "ring" on two nodes, "tube" of two materials and a
// texture, "sheet" without a material), a stream per mesh. Loaded by URL (on this thread and in
// workers) and parsed from an ArrayBuffer, every mesh of the scene reaches its stream's
// fullFaceCount with its own materials and node transform; a mesh whose extension is taken out of
// the JSON keeps its glTF base while the others refine.
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { after, before, test } from 'node:test';

import { binDir, rootDir, webDir } from './common.mjs';
import { gltfLoaderSite, launchChromium, pageErrors, serveViewer } from './serve.mjs';

let server, browser, site, json;

// A GLB's JSON chunk and BIN chunk.
function glbChunks(bytes) {
  const length = bytes.readUInt32LE(12);
  return { json: JSON.parse(bytes.subarray(20, 20 + length).toString('utf8')), bin: bytes.subarray(20 + length) };
}

// A GLB of `json` and a BIN chunk as glbChunks gives it (header included).
function glbBytes(gltf, bin) {
  let text = Buffer.from(JSON.stringify(gltf), 'utf8');
  text = Buffer.concat([text, Buffer.alloc((4 - (text.length % 4)) % 4, 0x20)]);
  const header = Buffer.alloc(20);
  header.write('glTF', 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(20 + text.length + bin.length, 8);
  header.writeUInt32LE(text.length, 12);
  header.write('JSON', 16);
  return Buffer.concat([header, text, bin]);
}

before(async () => {
  const work = mkdtempSync(path.join(tmpdir(), 'pmz-web-scene-'));
  execFileSync('python3', [path.join(rootDir, 'tests', 'tools', 'make_scene_gltf.py'), work]);
  site = path.join(work, 'site');
  gltfLoaderSite(site, webDir);
  const glb = path.join(site, 'scene.glb');
  execFileSync(path.join(binDir, 'pmz-encode'), [path.join(work, 'scene.gltf'), '-o', glb, '--quiet'],
    { stdio: ['ignore', 'ignore', 'ignore'] });
  const { json: gltf, bin } = glbChunks(readFileSync(glb));
  json = gltf;
  // The same scene with "sheet" (mesh 2) as a loader without the extension sees it.
  const plain = structuredClone(gltf);
  for (const p of plain.meshes[2].primitives) delete p.extensions;
  writeFileSync(path.join(site, 'plain.glb'), glbBytes(plain, bin));
  server = await serveViewer(site, {}, Infinity);
  browser = await launchChromium();
});
after(async () => {
  if (browser) await browser.closeAndClean();
  if (server) server.close();
  if (site) rmSync(path.dirname(site), { recursive: true, force: true });
});

// Loads `file` (by URL, or parsed from its bytes) with the plugin and waits for every stream;
// per three.js mesh: its node's name, its glTF mesh, the faces it draws, its stream's face count,
// the materials its faces use, its world scale, and whether it has a stream.
async function loadScene(file, { worker = false, parse = false } = {}) {
  const page = await browser.newPage();
  const errors = pageErrors(page);
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html`);
  const r = await page.evaluate(async (file, worker, parse) => {
    const THREE = await import('three');
    const { GLTFLoader } = await import('/jsm/loaders/GLTFLoader.js');
    const { PMZGLTFPlugin } = await import('/pmz/three.js');
    const loader = new GLTFLoader();
    loader.register((parser) => new PMZGLTFPlugin(parser, { worker }));
    const gltf = parse
      ? await loader.parseAsync(await (await fetch(`/${file}`)).arrayBuffer(), '/')
      : await loader.loadAsync(`/${file}`);
    await gltf.userData.pmzReady;
    const streams = gltf.userData.pmzStreams;
    const t0 = performance.now();
    while (streams.some((s) => !s.complete && !s.ended) && performance.now() - t0 < 60000)
      await new Promise((resolve) => requestAnimationFrame(resolve));
    const meshes = [];
    gltf.scene.updateMatrixWorld(true);
    gltf.scene.traverse((o) => {
      if (!o.isMesh) return;
      const g = o.geometry, stream = o.userData.pmzStream;
      const drawn = Math.min(g.drawRange.count, g.index.count) / 3;
      const list = Array.isArray(o.material) ? o.material : [o.material];
      const used = g.groups.length && Array.isArray(o.material)
        ? [...new Set(g.groups.filter((x) => x.start < drawn * 3).map((x) => list[x.materialIndex].name))]
        : [list[0].name];
      // The glTF node's object: the mesh, or the group of a mesh's primitives.
      const a = gltf.parser.associations;
      const node = o.parent.isGroup && a.get(o.parent)?.meshes === a.get(o).meshes ? o.parent : o;
      meshes.push({ node: node.name, mesh: a.get(o).meshes, drawn,
        faceCount: stream ? stream.faceCount : null, status: stream ? stream.status : null,
        used: used.sort(), scale: new THREE.Vector3().setFromMatrixScale(o.matrixWorld).x,
        x: new THREE.Vector3().setFromMatrixPosition(o.matrixWorld).x });
    });
    const renderer = new THREE.WebGLRenderer({ canvas: document.querySelector('canvas') });
    const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);
    camera.position.set(0, 0, 12);
    gltf.scene.add(new THREE.AmbientLight(0xffffff, 2));
    renderer.render(gltf.scene, camera);
    return { meshes, streams: streams.length, glError: renderer.getContext().getError() };
  }, file, worker, parse);
  await page.close();
  assert.deepEqual(errors, []);
  assert.equal(r.glError, 0);
  return r;
}

const full = (m) => json.meshes[m].primitives[0].extensions.PMZ_progressive_mesh.fullFaceCount;

for (const [how, options] of [['loaded by URL', {}], ['loaded by URL, workers', { worker: true }],
                              ['parsed from an ArrayBuffer', { parse: true }]]) {
  test(`GLTFLoader + PMZGLTFPlugin refines every mesh of a scene GLB (${how})`, async () => {
    const r = await loadScene('scene.glb', options);
    assert.equal(r.streams, 3, 'a stream per glTF mesh');
    const byNode = Object.fromEntries(r.meshes.map((m) => [m.node, m]));
    assert.deepEqual(Object.keys(byNode).sort(), ['ring-a', 'ring-b', 'sheet-node', 'tube-node']);
    assert.equal(r.meshes.length, 4, 'the tube\'s two primitives became one mesh');
    for (const m of r.meshes) {
      assert.equal(m.status, 'ok', m.node);
      assert.equal(m.faceCount, full(m.mesh), `${m.node}: the stream's full face count`);
      assert.equal(m.drawn, full(m.mesh), `${m.node}: draws every face`);
    }
    assert.deepEqual(byNode['ring-a'].used, ['gold']);
    assert.deepEqual(byNode['ring-b'].used, ['gold']);
    assert.deepEqual(byNode['tube-node'].used, ['blue', 'checker']);
    assert.deepEqual(byNode['sheet-node'].used, ['']);  // GLTFLoader's default material
    // Node transforms: root translation 0.5 in x; ring-b scaled 0.5 and moved 3 more.
    assert.ok(Math.abs(byNode['ring-a'].x - 0.5) < 1e-6 && Math.abs(byNode['ring-b'].x - 3.5) < 1e-6);
    assert.ok(Math.abs(byNode['ring-b'].scale - 0.5) < 1e-6 && Math.abs(byNode['ring-a'].scale - 1) < 1e-6);
  });
}

test('a mesh without the extension keeps its glTF base while the others refine', async () => {
  const r = await loadScene('plain.glb');
  assert.equal(r.streams, 2);
  for (const m of r.meshes) {
    if (m.node === 'sheet-node') {
      assert.equal(m.faceCount, null, 'no stream on the sheet');
      const base = json.accessors[json.meshes[2].primitives[0].indices].count / 3;
      assert.equal(m.drawn, base);
    } else {
      assert.equal(m.drawn, full(m.mesh), m.node);
    }
  }
});
