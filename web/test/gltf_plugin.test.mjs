// SPDX-License-Identifier: MIT
// PMZGLTFPlugin in headless Chromium: three's GLTFLoader with the plugin loads the GLB that
// pmz-encode writes for a textured mesh of two materials (tests/conformance/meshes/seamed.obj,
// its textures embedded); the glTF base shows first, then the mesh takes the stream's geometry
// and refines to the extension's fullFaceCount, with the decoder's render arrays (texture
// coordinates flipped to glTF's v down) and one material per glTF material; it draws.
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { copyFileSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { after, before, test } from 'node:test';

import { binDir, pngBytes, rootDir, webDir } from './common.mjs';
import { gltfLoaderSite, launchChromium, pageErrors, serveViewer } from './serve.mjs';

let server, browser, site;
const glbs = {};  // name: the GLB's JSON

// The GLB's JSON chunk.
function glbJson(bytes) {
  const length = bytes.readUInt32LE(12);
  return JSON.parse(bytes.subarray(20, 20 + length).toString('utf8'));
}

before(async () => {
  const work = mkdtempSync(path.join(tmpdir(), 'pmz-web-gltf-'));
  const meshes = path.join(rootDir, 'tests', 'conformance', 'meshes');
  for (const f of ['seamed.obj', 'seamed.mtl']) copyFileSync(path.join(meshes, f), path.join(work, f));
  writeFileSync(path.join(work, 'paint.png'), pngBytes(8, 8, () => [200, 40, 40]));
  writeFileSync(path.join(work, 'metal.png'), pngBytes(8, 8, (x) => (x % 2 ? [90, 90, 110] : [160, 160, 180])));
  writeFileSync(path.join(work, 'metal_n.png'), pngBytes(8, 8, () => [128, 128, 255]));
  site = path.join(work, 'site');
  gltfLoaderSite(site, webDir);
  // Simplified as far as possible the base is one triangle of one material (one primitive);
  // with --base-faces 100 it has faces of both (two primitives).
  for (const [name, args] of [['seamed.glb', []], ['seamed100.glb', ['--base-faces', '100']]]) {
    execFileSync(path.join(binDir, 'pmz-encode'), [path.join(work, 'seamed.obj'), '-o',
      path.join(site, name), '--quiet', ...args], { stdio: ['ignore', 'ignore', 'inherit'] });
    glbs[name] = glbJson(readFileSync(path.join(site, name)));
  }
  server = await serveViewer(site, {}, Infinity);
  browser = await launchChromium();
});
after(async () => {
  if (browser) await browser.closeAndClean();
  if (server) server.close();
  if (site) rmSync(path.dirname(site), { recursive: true, force: true });
});

for (const [file, worker] of [['seamed100.glb', false], ['seamed100.glb', true], ['seamed.glb', false]]) {
  test(`GLTFLoader + PMZGLTFPlugin refines ${file}'s mesh to its full face count (worker ${worker})`, async () => {
    const json = glbs[file], ext = json.meshes[0].primitives[0].extensions.PMZ_progressive_mesh;
    const page = await browser.newPage();
    const errors = pageErrors(page);
    await page.goto(`http://127.0.0.1:${server.address().port}/index.html`);
    const r = await page.evaluate(async (file, worker) => {
      const THREE = await import('three');
      const { GLTFLoader } = await import('/jsm/loaders/GLTFLoader.js');
      const { PMZGLTFPlugin } = await import('/pmz/three.js');
      const loader = new GLTFLoader();
      loader.register((parser) => new PMZGLTFPlugin(parser, { worker }));
      const gltf = await loader.loadAsync(`/${file}`);
      const meshesOf = () => {
        const list = [];
        gltf.scene.traverse((o) => { if (o.isMesh) list.push(o); });
        return list;
      };
      // As GLTFLoader made it: one mesh per primitive (material), the base's faces.
      const before = meshesOf().map((m) => ({ faces: m.geometry.index.count / 3, hasStream: !!m.userData.pmzStream }));
      await gltf.userData.pmzReady;
      const stream = gltf.userData.pmzStreams[0];
      const t0 = performance.now();
      while (!stream.complete && !stream.ended && performance.now() - t0 < 60000)
        await new Promise((resolve) => requestAnimationFrame(resolve));
      const meshes = meshesOf();
      const mesh = meshes[0];
      const g = mesh.geometry;
      const snap = await stream.snapshot();
      const render = snap.render;
      const uv = g.getAttribute('uv').array, suv = render.attributes.uv;
      let uvFlipped = suv.length > 0;
      for (let i = 0; i < suv.length; i += 2)
        if (uv[i] !== suv[i] || Math.abs(uv[i + 1] - (1 - suv[i + 1])) > 1e-6) uvFlipped = false;
      const count = render.positions.length / 3;
      const samePositions = render.positions.every((v, i) => g.getAttribute('position').array[i] === v);
      const sameIndices = render.indices.every((v, i) => g.index.array[i] === v);
      const renderer = new THREE.WebGLRenderer({ canvas: document.querySelector('canvas') });
      const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);
      const box = new THREE.Box3().setFromObject(gltf.scene);
      camera.position.copy(box.getCenter(new THREE.Vector3())).add(new THREE.Vector3(0, 0, 3));
      camera.lookAt(box.getCenter(new THREE.Vector3()));
      gltf.scene.add(new THREE.AmbientLight(0xffffff, 2));
      renderer.render(gltf.scene, camera);
      const gl = renderer.getContext();
      return {
        before, status: stream.status, complete: stream.complete,
        meshes: meshes.length, sameGeometry: g === stream.geometry, drawn: g.drawRange.count / 3,
        faceCount: stream.faceCount, groups: g.groups.length,
        materials: Array.isArray(mesh.material) ? mesh.material.map((m) => m.name) : [mesh.material.name],
        maps: Array.isArray(mesh.material) ? mesh.material.map((m) => !!m.map) : [],
        uvFlipped, samePositions, sameIndices, count, programs: renderer.info.programs.length,
        glError: gl.getError(),
      };
    }, file, worker);
    await page.close();
    assert.deepEqual(errors, []);
    assert.equal(r.before.length, json.meshes[0].primitives.length, 'a mesh per primitive before the stream');
    assert.ok(r.before.every((m) => !m.hasStream));
    assert.equal(r.status, 'ok');
    assert.ok(r.complete);
    assert.equal(r.meshes, 1, 'the primitives became one mesh');
    assert.ok(r.sameGeometry);
    assert.equal(r.faceCount, ext.fullFaceCount);
    assert.equal(r.drawn, ext.fullFaceCount);
    assert.ok(r.groups >= 2, 'groups per material run');
    assert.deepEqual(r.materials, ['paint', 'metal']);
    assert.deepEqual(r.maps, [true, true]);
    assert.ok(r.uvFlipped, 'uv is 1 - v of the stream (glTF)');
    assert.ok(r.samePositions && r.sameIndices, 'the geometry is the decoder render arrays');
    assert.ok(r.programs > 0);
    assert.equal(r.glError, 0);
  });
}
