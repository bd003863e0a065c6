// SPDX-License-Identifier: MIT
// View-dependent decoding in the package (node): the decoder's view calls against the native
// decoder, and RangeSource / loadView reading a stream with a node table by ranges from a local
// server that honours Range (and from servers that ignore it, lie about it or stall).
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { after, before, test } from 'node:test';

import { binDir, importPackage, importThreeLoader, nativeDecode, rootDir, sameBits } from './common.mjs';
import { serveViewer } from './serve.mjs';

// A terrain of about 60k faces encoded with a node table (clusters of 1000 vertices: about a
// hundred nodes, nodeCount).
let nodesPmz, nodeCount, server, base;
const CLOSE = { eye: [0.2, 0.2, 0.15], target: [0.1, 0.1, 0], width: 800, height: 600, pixelError: 1 };
const FAR = { eye: [0.5, 0.5, 3], target: [0.5, 0.5, 0], pixelError: 0 };

before(async () => {
  const dir = mkdtempSync(path.join(tmpdir(), 'pmz-view-'));
  const ply = path.join(dir, 'terrain.ply');
  nodesPmz = path.join(dir, 'terrain.pmz');
  execFileSync(path.join(binDir, 'pmz-generate'), ['--faces', '60000', '-q', '-o', ply]);
  execFileSync(path.join(binDir, 'pmz-encode'), [ply, '--cluster-vertices', '1000', '-o', nodesPmz],
    { stdio: ['ignore', 'ignore', 'inherit'] });
  nodeCount = JSON.parse(execFileSync(path.join(binDir, 'pmz-info'), ['--json', nodesPmz])).nodes;
  // (20 KB: more than the first range)
  const plain = path.join(rootDir, 'tests', 'conformance', 'vectors', 'torus-speed.pmz');
  server = await serveViewer(dir, {
    'nodes.pmz': { file: nodesPmz }, 'ignore.pmz': { file: nodesPmz, range: 'ignore' },
    'wrong.pmz': { file: nodesPmz, range: 'wrongrange' }, 'stall.pmz': { file: nodesPmz, range: 'stall' },
    'plain.pmz': { file: plain },
  }, Infinity);
  base = `http://127.0.0.1:${server.address().port}/stream/`;
});
after(() => {
  server.closeAllConnections();
  server.close();
});

function nativeView(file, v, more = []) {
  return nativeDecode(file, ['--camera', [...v.eye, ...v.target].join(','), '--pixel-error',
    String(v.pixelError), '--size', `${v.width ?? 1920}x${v.height ?? 1080}`, ...more]);
}

// The decoder's mesh without the faces of nodes not applied (degenerate) and the vertices no
// face uses, numbered in first use: what pmz-decode --camera writes.
function dropUnused(d) {
  const ix = d.indices(), p = d.positions();
  const indices = [], positions = [], remap = new Map();
  for (let f = 0; f < ix.length; f += 3) {
    if (ix[f] === ix[f + 1]) continue;
    for (let k = 0; k < 3; ++k) {
      const v = ix[f + k];
      if (!remap.has(v)) {
        remap.set(v, positions.length / 3);
        positions.push(p[3 * v], p[3 * v + 1], p[3 * v + 2]);
      }
      indices.push(remap.get(v));
    }
  }
  return { indices: Uint32Array.from(indices), positions: Float32Array.from(positions) };
}

// The view's mesh by ranges from `name`: checked against pmz-decode --camera's; the result.
async function closeViewAgainstNative(name) {
  const { createDecoder, loadView } = await importPackage();
  const d = await createDecoder();
  const result = await loadView(d, base + name, await view(d, CLOSE));
  assert.equal(result.status, 'ok');
  assert.equal(result.complete, true);
  const mine = dropUnused(d), native = nativeView(nodesPmz, CLOSE);
  assert.equal(mine.indices.length, native.indices.length);
  assert.ok(sameBits(mine.indices, native.indices), 'indices differ');
  assert.ok(sameBits(mine.positions, native.positions), 'positions differ');
  result.nodesApplied = d.nodesApplied();
  d.dispose();
  return result;
}

async function view(d, v) {
  return d.lookAt(v.eye, v.target, { width: v.width, height: v.height, pixelError: v.pixelError });
}

test('the view calls before and after the node table, and node bytes checked', async () => {
  const { createDecoder } = await importPackage();
  const bytes = readFileSync(nodesPmz);
  const d = await createDecoder();
  assert.equal(d.nodeRange(1), null);
  assert.deepEqual(d.nodesToFetch(), []);
  assert.equal(d.nodeCount, 0);
  assert.equal(d.nodesApplied(), 0);
  assert.equal(d.updateView(await view(d, FAR)), 0);  // no base mesh yet
  assert.equal(d.viewComplete(), false);
  // In order up to the table: node 1's range starts where the in-order bytes may stop.
  let at = 0;
  while (!d.nodeRange(1)) {
    assert.equal(d.feed(bytes.subarray(at, at + 1024)), 'ok');
    at += 1024;
  }
  assert.equal(d.nodeCount, nodeCount);
  const r1 = d.nodeRange(1), last = d.nodeRange(nodeCount - 1);
  assert.ok(r1.offset > 0 && r1.size > 0);
  assert.equal(last.offset + last.size < bytes.length, true);
  assert.equal(d.nodeRange(nodeCount), null);
  d.updateView(await view(d, FAR));
  // Node 0, and the nodes whose bytes the slices fed in order already hold (they follow the
  // table in file order; the far view sees every node).
  let arrived = 1;
  while (arrived < nodeCount && d.nodeRange(arrived).offset + d.nodeRange(arrived).size <= at) ++arrived;
  assert.equal(d.nodesApplied(), arrived);
  const want = d.nodesToFetch();
  assert.ok(want.length > 0 && want.every((k) => k >= 1 && k < nodeCount), String(want));
  // A node's bytes cut short: the stream fails with a line naming the node; the mesh stays.
  const k = want[0], r = d.nodeRange(k);
  assert.equal(d.feedNode(k, bytes.subarray(r.offset, r.offset + r.size - 1)), 'corrupt');
  assert.match(d.error, /^pmz: .*node/);
  assert.equal(d.feedNode(k, bytes.subarray(r.offset, r.offset + r.size)), 'corrupt');  // sticky
  assert.ok(d.faceCount > 0);
  d.dispose();
});

test('the all-nodes view by ranges gives the whole stream\'s indices and positions', async () => {
  const { createDecoder, loadView } = await importPackage();
  const whole = await createDecoder();
  assert.equal(whole.feed(readFileSync(nodesPmz)), 'ok');
  assert.equal(whole.finish(), 'ok');
  whole.refine();
  const d = await createDecoder();
  const result = await loadView(d, base + 'nodes.pmz', await view(d, FAR), { maxSplits: 500 });
  assert.equal(result.status, 'ok');
  assert.equal(result.complete, true);
  assert.equal(result.inOrder, false);
  // No byte twice: the node the in-order reading stopped in is read on from there.
  assert.ok(result.bytes <= result.totalBytes, `${result.bytes} of ${result.totalBytes} bytes`);
  assert.equal(d.nodesApplied(), nodeCount);
  assert.ok(sameBits(d.indices(), whole.indices()), 'indices differ');
  assert.ok(sameBits(d.positions(), whole.positions()), 'positions differ');
  assert.ok(server.ranges['nodes.pmz'].every((h) => /^bytes=\d+-\d+$/.test(h)));
  whole.dispose();
  d.dispose();
});

test('a close view fetches part of the file and matches pmz-decode --camera', async () => {
  const result = await closeViewAgainstNative('nodes.pmz');
  assert.equal(result.totalBytes, readFileSync(nodesPmz).length);
  // (A corner of the terrain in view: its nodes and all their parents, about half of the bytes.)
  assert.ok(result.bytes < result.totalBytes * 0.6, `${result.bytes} of ${result.totalBytes} bytes`);
  assert.ok(result.nodesApplied > 1 && result.nodesApplied < nodeCount);
});

test('maxFaces bounds the faces a view applies and fetches, as pmz-decode --max-faces', async () => {
  const { createDecoder, loadView } = await importPackage();
  const free = await createDecoder();
  const all = await loadView(free, base + 'nodes.pmz', await view(free, CLOSE));
  const faces = dropUnused(free).indices.length / 3;
  free.dispose();
  const budget = Math.floor(faces / 2);
  const d = await createDecoder();
  const result = await loadView(d, base + 'nodes.pmz', await view(d, CLOSE), { maxFaces: budget });
  assert.equal(result.status, 'ok');
  assert.equal(result.complete, true);
  const mine = dropUnused(d);
  assert.ok(mine.indices.length / 3 <= budget, `${mine.indices.length / 3} faces, budget ${budget}`);
  assert.ok(mine.indices.length / 3 > d.info().baseFaces, 'nothing refined');
  assert.ok(result.bytes < all.bytes, `${result.bytes} bytes, ${all.bytes} without the budget`);
  const native = nativeView(nodesPmz, CLOSE, ['--max-faces', String(budget)]);
  assert.ok(sameBits(mine.indices, native.indices), 'indices differ from pmz-decode --max-faces');
  assert.ok(sameBits(mine.positions, native.positions), 'positions differ');
  // A lower budget undoes nodes; 0 is none again: the view's whole mesh.
  const applied = d.nodesApplied();
  d.setViewFaceBudget(Math.floor(budget / 2));
  d.updateView(await view(d, CLOSE));
  assert.ok(d.nodesApplied() < applied && dropUnused(d).indices.length / 3 <= budget / 2);
  assert.equal(d.viewComplete(), true);
  const again = await loadView(d, base + 'nodes.pmz', await view(d, CLOSE), { maxFaces: 0 });
  assert.equal(again.complete, true);
  assert.equal(dropUnused(d).indices.length / 3, faces);
  d.dispose();
});

test('three.js: view.maxFaces bounds the faces update(camera) draws', async () => {
  const THREE = await import(path.join(rootDir, 'web', 'node_modules', 'three', 'build', 'three.module.js'));
  const { PMZLoader } = await importThreeLoader();
  const loader = new PMZLoader(undefined, { view: { pixelError: 1, viewportHeight: 600, maxFaces: 1 } });
  const s = await loader.stream(base + 'nodes.pmz');
  assert.equal(await s.done, 'ok');
  assert.equal(s.maxFaces, 1);
  const camera = new THREE.PerspectiveCamera(60, 800 / 600, 1e-3, 100);
  camera.position.set(...CLOSE.eye);
  camera.lookAt(new THREE.Vector3(...CLOSE.target));
  const drawn = () => dropUnused(s.decoder).indices.length / 3;
  await follow(s, camera, null);
  assert.equal(s.nodesApplied, 1);  // node 0 alone, whatever the budget
  const floor = drawn();
  s.maxFaces = 0;
  await follow(s, camera, null);
  const all = drawn(), nodes = s.nodesApplied;
  const budget = Math.floor((floor + all) / 2);
  s.maxFaces = budget;
  await follow(s, camera, null);
  assert.ok(drawn() > floor && drawn() <= budget && s.nodesApplied < nodes,
    `${drawn()} faces from ${s.nodesApplied} nodes; budget ${budget}, ${all} faces from ${nodes} nodes without`);
  s.dispose();
});

test('a server that ignores Range: the stream is read in order, same mesh', async () => {
  const result = await closeViewAgainstNative('ignore.pmz');
  assert.equal(result.inOrder, true);
  assert.equal(result.requests, 1);
  assert.ok(result.bytes >= result.totalBytes);
});

test('a stream without a node table is read in order to its end', async () => {
  const { createDecoder, loadView } = await importPackage();
  const d = await createDecoder();
  const result = await loadView(d, base + 'plain.pmz', await view(d, FAR));
  assert.equal(result.status, 'ok');
  assert.equal(result.inOrder, true);
  assert.equal(result.complete, true);
  const native = nativeDecode(path.join(rootDir, 'tests', 'conformance', 'vectors', 'torus-speed.pmz'));
  assert.ok(sameBits(d.indices(), native.indices), 'indices differ');
  assert.ok(sameBits(d.positions(), native.positions), 'positions differ');
  d.dispose();
});

test('a wrong Content-Range, a stalled body, a missing file: one line, no hang', async () => {
  const { createDecoder, loadView } = await importPackage();
  for (const [name, pattern] of [['wrong.pmz', /Content-Range "bytes 1-16384\/\d+"/],
    ['stall.pmz', /no data for 0\.3 s/], ['missing.pmz', /HTTP 404/]]) {
    const d = await createDecoder();
    const t0 = Date.now();
    await assert.rejects(loadView(d, base + name, await view(d, CLOSE), { timeoutMs: 300 }), (e) => {
      assert.match(e.message, pattern);
      assert.ok(e.message.startsWith(`pmz: ${base}${name} (bytes=0-16383): `), e.message);
      assert.ok(!e.message.includes('\n'));
      return true;
    });
    assert.ok(Date.now() - t0 < 5000);
    d.dispose();
  }
});

// PMZViewStream.update(camera, mesh) until the view is complete (or failed).
async function follow(s, camera, mesh) {
  for (let i = 0; i < 2000 && !(s.update(camera, mesh, 50), s.complete || s.ended); ++i)
    await new Promise((resolve) => setTimeout(resolve, 2));
  assert.equal(s.error, '');
  assert.ok(s.complete, 'the view never completed');
}

// The geometry drawn (the draw range) against the decoder's arrays.
function assertGeometryIsDecoders(s) {
  const g = s.geometry, d = s.decoder;
  assert.equal(g.drawRange.count, 3 * d.faceCount);
  assert.ok(sameBits(g.getIndex().array.slice(0, 3 * d.faceCount), d.indices()), 'indices differ');
  assert.ok(sameBits(g.getAttribute('position').array.slice(0, 3 * d.vertexCount), d.positions()),
    'positions differ');
}

test('three.js: update(camera, mesh) fetches what a moving camera needs and uploads it', async () => {
  const THREE = await import(path.join(rootDir, 'web', 'node_modules', 'three', 'build', 'three.module.js'));
  const { PMZLoader } = await importThreeLoader();
  const { createDecoder } = await importPackage();
  const loader = new PMZLoader(undefined, { view: { pixelError: 1, viewportHeight: 600 } });
  const s = await loader.stream(base + 'nodes.pmz');
  assert.equal(await s.done, 'ok');
  // The mesh moved and scaled, the camera with it: the view in the mesh's coordinates is
  // CLOSE's.
  const mesh = new THREE.Mesh(s.geometry);
  mesh.position.set(5, -1, 2);
  mesh.scale.setScalar(2);
  mesh.updateMatrixWorld();
  const camera = new THREE.PerspectiveCamera(60, 800 / 600, 1e-3, 100);
  const place = (v) => {
    camera.position.copy(new THREE.Vector3(...v.eye).applyMatrix4(mesh.matrixWorld));
    camera.lookAt(new THREE.Vector3(...v.target).applyMatrix4(mesh.matrixWorld));
    camera.updateMatrixWorld();
  };
  place(CLOSE);
  await follow(s, camera, mesh);
  const close = s.nodesApplied;
  assert.ok(close > 1 && close < nodeCount, `${close} nodes`);
  assert.ok(s.bytes < s.totalBytes * 0.6, `${s.bytes} of ${s.totalBytes} bytes`);
  assertGeometryIsDecoders(s);
  // Every node (the whole stream's mesh), then back: nodes undone, the geometry follows.
  place(FAR);
  s.pixelError = FAR.pixelError;
  await follow(s, camera, mesh);
  assert.equal(s.nodesApplied, nodeCount);
  assertGeometryIsDecoders(s);
  const whole = await createDecoder();
  assert.equal(whole.feed(readFileSync(nodesPmz)), 'ok');
  whole.refine();
  assert.ok(sameBits(s.decoder.indices(), whole.indices()), 'indices differ from the whole stream\'s');
  whole.dispose();
  place(CLOSE);
  s.pixelError = CLOSE.pixelError;
  await follow(s, camera, mesh);
  assert.equal(s.nodesApplied, close);
  assertGeometryIsDecoders(s);
  s.dispose();
});

test('three.js: a view stream whose request fails ends with one line, done unawaited', async () => {
  const { PMZLoader } = await importThreeLoader();
  const s = await new PMZLoader(undefined, { view: true }).stream(base + 'missing.pmz');
  for (let i = 0; i < 500 && !s.ended; ++i) {
    await new Promise((resolve) => setTimeout(resolve, 5));
    s.update();
  }
  assert.equal(s.ended, true);
  assert.match(s.error, /^pmz: .*missing\.pmz \(bytes=0-16383\): HTTP 404$/);
  s.dispose();
});
