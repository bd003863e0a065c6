// SPDX-License-Identifier: MIT
// createDecoder({ workers }): in node (shared memory always there: the threaded module for more
// than one) a stream with a node table decoded with 1 and 2 workers, fed whole and in slices,
// gives the same positions, indices and change reports, the native decoder's mesh, and with 2
// the decoder's threads did start; the fallbacks to one worker; in headless Chromium, a page
// served cross-origin isolated decodes on 2, one that is not on 1, to the same mesh.
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { cpSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { before, test } from 'node:test';
import { pathToFileURL } from 'node:url';

import { binDir, importPackage, nativeDecode, sameBits, webDir } from './common.mjs';
import { launchChromium, pageErrors, serveViewer } from './serve.mjs';

// A terrain of about 60k faces with a node table (clusters of 1000 vertices: about a hundred nodes).
let nodesPmz, bytes;
before(() => {
  const dir = mkdtempSync(path.join(os.tmpdir(), 'pmz-threads-'));
  const ply = path.join(dir, 'terrain.ply');
  nodesPmz = path.join(dir, 'terrain.pmz');
  execFileSync(path.join(binDir, 'pmz-generate'), ['--faces', '60000', '-q', '-o', ply]);
  execFileSync(path.join(binDir, 'pmz-encode'), [ply, '--cluster-vertices', '1000', '-o', nodesPmz],
    { stdio: ['ignore', 'ignore', 'inherit'] });
  bytes = readFileSync(nodesPmz);
});

// A deterministic sequence of slice sizes and refine amounts (xorshift).
function* randomSizes(seed, max) {
  let x = seed;
  for (;;) {
    x ^= x << 13; x >>>= 0;
    x ^= x >>> 17;
    x ^= x << 5; x >>>= 0;
    yield 1 + (x % max);
  }
}

// Decodes `bytes` with `workers`, fed by `plan` (whole, slices: each slice then refine()
// everything, random: random slices, each then refine(random)), recording after each step the
// counts and the change report (then clearChanges()). The final arrays are copies.
async function decode(workers, plan) {
  const { createDecoder } = await importPackage();
  const d = await createDecoder({ workers });
  const steps = [];
  const record = () => {
    const c = d.changes();
    steps.push({ vertices: d.vertexCount, faces: d.faceCount, splits: d.splitsApplied, all: c.all,
      vertexBegin: c.vertexBegin, faceBegin: c.faceBegin, wedgeBegin: c.wedgeBegin,
      modified: Array.from(c.modifiedFaces) });
    d.clearChanges();
  };
  if (plan === 'whole') {
    assert.equal(d.feed(bytes), 'ok');
    d.refine();
    record();
  } else {
    const sizes = plan === 'slices' ? null : randomSizes(12345, 20000);
    const amounts = randomSizes(777, 30000);
    for (let at = 0; at < bytes.length;) {
      const n = sizes ? sizes.next().value : 4093;
      assert.equal(d.feed(bytes.subarray(at, at + n)), 'ok');
      at += n;
      d.refine(sizes ? amounts.next().value : undefined);
      record();
    }
    d.refine();
    record();
  }
  assert.equal(d.finish(), 'ok');
  assert.equal(d.status, 'ok', d.error);
  const out = { workers: d.workers, threadStarts: d._m.threadStarts ?? 0, steps,
    positions: d.positions().slice(), indices: d.indices().slice(), parents: d.splitParents().slice() };
  d.dispose();
  return out;
}

for (const plan of ['whole', 'slices', 'random']) {
  test(`workers 1 and 2 decode a stream with nodes alike (${plan})`, async () => {
    const one = await decode(1, plan), two = await decode(2, plan);
    assert.equal(one.workers, 1);
    assert.equal(two.workers, 2);
    assert.ok(two.threadStarts > 0, 'no decoding thread started');
    assert.equal(one.threadStarts, 0);
    assert.deepEqual(two.steps, one.steps, 'change reports differ');
    assert.ok(sameBits(two.positions, one.positions), 'positions differ');
    assert.ok(sameBits(two.indices, one.indices), 'indices differ');
    assert.ok(sameBits(two.parents, one.parents), 'split parents differ');
    const native = nativeDecode(nodesPmz);
    assert.ok(sameBits(two.indices, native.indices), 'indices differ from pmz-decode');
    assert.ok(sameBits(two.positions, native.positions), 'positions differ from pmz-decode');
  });
}

test('face targets with 2 workers give the mesh of 1', async () => {
  const { createDecoder } = await importPackage();
  const [one, two] = [await createDecoder({ workers: 1 }), await createDecoder({ workers: 2 })];
  for (const d of [one, two]) assert.equal(d.feed(bytes), 'ok');
  const starts = two._m.threadStarts;
  for (const faces of [20000, 45000, 30000, Infinity, 5000]) {
    for (const d of [one, two]) d.setFaceTarget(faces);
    assert.equal(two.faceCount, one.faceCount);
    assert.ok(sameBits(two.indices(), one.indices()), `indices differ at ${faces} faces`);
    assert.ok(sameBits(two.positions(), one.positions()), `positions differ at ${faces} faces`);
  }
  assert.ok(two._m.threadStarts > starts, 'no decoding thread started');
  one.dispose();
  two.dispose();
});

test('workers: the default is the cores; one, or wasmBinary, the single-threaded module', async () => {
  const { createDecoder } = await importPackage();
  const cores = typeof os.availableParallelism === 'function' ? os.availableParallelism() : os.cpus().length;
  const d = await createDecoder();
  assert.equal(d.workers, cores);
  d.dispose();
  for (const options of [{ workers: 1 }, { workers: 0 }, { workers: NaN }]) {
    const s = await createDecoder(options);
    assert.equal(s.workers, 1);
    assert.equal(s._m.threadStarts, undefined);  // (the single-threaded module)
    s.dispose();
  }
  const wasmBinary = readFileSync(path.join(webDir, 'dist', 'pkg', 'pmz_wasm.wasm'));
  const b = await createDecoder({ workers: 2, wasmBinary });
  assert.equal(b.workers, 1);
  assert.equal(b.feed(bytes), 'ok');
  b.refine();
  assert.equal(b.faceCount, nativeDecode(nodesPmz).indices.length / 3);
  b.dispose();
});

test('workers: a threaded module that fails to load leaves one worker', async () => {
  const dir = mkdtempSync(path.join(os.tmpdir(), 'pmz-threads-pkg-'));
  cpSync(path.join(webDir, 'dist', 'pkg'), dir, { recursive: true });
  rmSync(path.join(dir, 'pmz_wasm_mt.wasm'));
  const { createDecoder } = await import(pathToFileURL(path.join(dir, 'index.js')).href);
  const d = await createDecoder({ workers: 2 });
  assert.equal(d.workers, 1);
  assert.equal(d.feed(bytes), 'ok');
  d.refine();
  assert.ok(sameBits(d.indices(), nativeDecode(nodesPmz).indices));
  d.dispose();
});

// In headless Chromium: a page served cross-origin isolated (/coi/) decodes with 2 workers on
// the threaded module, one that is not falls back to 1; both give the native decoder's mesh,
// fed whole and in slices.
test('browsers: 2 workers where the page is cross-origin isolated, else 1', async () => {
  const site = mkdtempSync(path.join(os.tmpdir(), 'pmz-threads-site-'));
  cpSync(path.join(webDir, 'dist', 'pkg'), path.join(site, 'pmz'), { recursive: true });
  writeFileSync(path.join(site, 'index.html'), '<!doctype html><title>pmz threads</title>\n');
  const server = await serveViewer(site, { 'nodes.pmz': { file: nodesPmz } }, Infinity);
  const browser = await launchChromium();
  const digest = (a) => createHash('sha256').update(new Uint8Array(a.buffer, a.byteOffset, a.byteLength))
    .digest('hex');
  const native = nativeDecode(nodesPmz);
  try {
    for (const [prefix, isolated] of [['/coi/', true], ['/', false]]) {
      const page = await browser.newPage();
      const errors = pageErrors(page);
      const base = `http://127.0.0.1:${server.address().port}${prefix}`;
      await page.goto(base + 'index.html');
      const out = await page.evaluate(async (b) => {
        const { createDecoder } = await import(b + 'pmz/index.js');
        const bytes = new Uint8Array(await (await fetch(b + 'stream/nodes.pmz')).arrayBuffer());
        const hex = async (a) => Array.from(new Uint8Array(await crypto.subtle.digest('SHA-256', a.slice())))
          .map((x) => x.toString(16).padStart(2, '0')).join('');
        const runs = [];
        for (const [workers, slice] of [[1, bytes.length], [2, bytes.length], [2, 4093]]) {
          const d = await createDecoder({ workers });
          for (let at = 0; at < bytes.length; at += slice) {
            d.feed(bytes.subarray(at, at + slice));
            d.refine();
          }
          runs.push({ workers: d.workers, threadStarts: d._m.threadStarts ?? 0, status: d.finish(),
            positions: await hex(d.positions()), indices: await hex(d.indices()) });
          d.dispose();
        }
        return { isolated: self.crossOriginIsolated, runs };
      }, base);
      await page.close();
      assert.deepEqual(errors, []);
      assert.equal(out.isolated, isolated);
      assert.deepEqual(out.runs.map((r) => r.workers), isolated ? [1, 2, 2] : [1, 1, 1]);
      for (const r of out.runs) {
        assert.equal(r.status, 'ok');
        assert.equal(r.positions, digest(native.positions));
        assert.equal(r.indices, digest(native.indices));
        if (r.workers === 2) assert.ok(r.threadStarts > 0, 'no decoding thread started');
      }
    }
  } finally {
    await browser.closeAndClean();
    server.close();
  }
});
