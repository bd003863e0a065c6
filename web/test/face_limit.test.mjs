// SPDX-License-Identifier: MIT
// PMZStream.faceLimit (node, three's BufferGeometry without a renderer): following the stream,
// the geometry shows at most the limit's faces while bytes arrive, each level it shows is a
// level of the stream (equal to a fresh decoder's at that face count), and once every byte is
// in and decoded it shows the finest level, equal to the native decoder's mesh. The base mesh
// is shown before any refinement.
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { test } from 'node:test';

import { demoPmz, importPackage, importThreeLoader, nativeDecode, sameBits } from './common.mjs';

// The geometry's drawn positions and indices.
function drawn(s) {
  const g = s.geometry, nf = g.drawRange.count / 3;
  const indices = g.getIndex().array.slice(0, 3 * nf);
  const nv = s.vertexCount;
  return { positions: g.getAttribute('position').array.slice(0, 3 * nv), indices };
}

// A fresh decoder's mesh at `faces` faces from the same bytes.
async function levelAt(bytes, faces) {
  const { createDecoder } = await importPackage();
  const d = await createDecoder();
  assert.equal(d.feed(bytes), 'ok');
  d.setFaceTarget(faces);
  const out = { positions: d.positions().slice(), indices: d.indices().slice() };
  d.dispose();
  return out;
}

test('faceLimit holds the shown level while bytes arrive, then the finest level', async () => {
  const { createDecoder } = await importPackage();
  const { PMZStream } = await importThreeLoader();
  const bytes = readFileSync(demoPmz());
  const limit = 5000;
  const s = new PMZStream(await createDecoder(), { faceLimit: limit });
  let baseChecked = false, shownAtLimit = 0;
  for (let at = 0; at < bytes.length; at += 4096) {
    assert.equal(s.feed(bytes.subarray(at, at + 4096)), 'ok');
    const changed = s.update(50);
    const info = s.info();
    if (!info.baseDone) continue;
    if (!baseChecked) {  // the first update with the base mesh shows it unrefined
      assert.ok(changed);
      assert.equal(s.faceCount, info.baseFaces);
      baseChecked = true;
    }
    assert.ok(s.faceCount <= limit, `${s.faceCount} faces shown at byte ${at}`);
    assert.equal(s.geometry.drawRange.count, 3 * s.faceCount);
    if (s.faceCount > limit - 2) ++shownAtLimit;
  }
  assert.ok(baseChecked);
  assert.ok(shownAtLimit > 0, 'the limit was never reached');
  // A level of the stream: the one a decoder set to that face count has.
  const held = drawn(s);
  const reference = await levelAt(bytes, s.faceCount);
  assert.equal(reference.indices.length, held.indices.length);
  assert.ok(sameBits(held.positions, reference.positions) && sameBits(held.indices, reference.indices),
    'the held level differs from the stream\'s level at that face count');
  // Every byte in: decoding goes on past the limit, the geometry keeps the held level until
  // the last split, then shows the finest level.
  assert.equal(s.finish(), 'ok');
  let updates = 0;
  while (!s.complete) {
    const before = s.faceCount;
    s.update(1);
    if (!s.complete) assert.equal(s.faceCount, before, 'a level between the limit and the finest was shown');
    assert.ok(++updates < 100000);
  }
  assert.ok(updates > 1, 'decoded in one update: nothing was held back');
  const native = nativeDecode(demoPmz());
  const full = drawn(s);
  assert.equal(s.faceCount, native.indices.length / 3);
  assert.ok(sameBits(full.positions, native.positions) && sameBits(full.indices, native.indices),
    'the finest level differs from pmz-decode\'s');
  s.dispose();
});

test('faceLimit null follows the stream; a raised limit lets it refine on', async () => {
  const { createDecoder } = await importPackage();
  const { PMZStream } = await importThreeLoader();
  const bytes = readFileSync(demoPmz());
  const s = new PMZStream(await createDecoder(), { faceLimit: 1000 });
  assert.equal(s.feed(bytes.subarray(0, bytes.length >> 1)), 'ok');
  for (let i = 0; i < 50; ++i) s.update(50);
  assert.ok(s.faceCount <= 1000 && s.faceCount > 990, `${s.faceCount}`);
  s.faceLimit = 3000;
  for (let i = 0; i < 50; ++i) s.update(50);
  assert.ok(s.faceCount <= 3000 && s.faceCount > 2990, `${s.faceCount}`);
  s.faceLimit = null;
  for (let i = 0; i < 200; ++i) s.update(50);
  assert.equal(s.faceCount, s.decoder.faceCount);
  assert.ok(s.faceCount > 3000);
  assert.equal(s.decoder.splitsApplied, s.decoder.splitsAvailable);
  s.dispose();
});

// A truncated stream (the sample's first 60,000 bytes) through PMZLoader as an application
// uses it (autoUpdate: update() every animation frame): once the error is in, refinement goes
// on to the level a plain decoder reaches (feed, finish, refine: pmz-decode --salvage's), the
// geometry shows it, and the stream ends there with the error.
test('PMZLoader refines a truncated stream up to what arrived, then ends', async () => {
  const { createDecoder } = await importPackage();
  const { PMZLoader } = await importThreeLoader();
  const bytes = readFileSync(demoPmz()).subarray(0, 60000);
  const d = await createDecoder();
  assert.equal(d.feed(bytes), 'ok');
  assert.equal(d.finish(), 'truncated');
  d.refine();
  const salvage = { positions: d.positions().slice(), indices: d.indices().slice() };
  d.dispose();
  const hadFrames = 'requestAnimationFrame' in globalThis;
  const saved = globalThis.requestAnimationFrame;
  globalThis.requestAnimationFrame = (f) => setTimeout(() => f(performance.now()), 4);
  try {
    for (const faceLimit of [null, 1000]) {
      const s = await new PMZLoader(undefined, { faceLimit }).stream(new Blob([bytes]));
      assert.equal(await s.done, 'truncated');
      const deadline = Date.now() + 30000;
      while (!s.ended) {
        assert.ok(Date.now() < deadline, `not ended: ${s.faceCount} faces`);
        await new Promise((r) => setTimeout(r, 20));
      }
      assert.equal(s.status, 'truncated');
      assert.match(s.error, /truncated/);
      assert.equal(s.complete, false);
      const shown = drawn(s);
      assert.equal(s.faceCount, salvage.indices.length / 3, `faceLimit ${faceLimit}`);
      assert.ok(sameBits(shown.positions, salvage.positions) && sameBits(shown.indices, salvage.indices),
        `faceLimit ${faceLimit}: the geometry differs from the decoder's last good level`);
      s.dispose();
    }
  } finally {
    if (hadFrames) globalThis.requestAnimationFrame = saved; else delete globalThis.requestAnimationFrame;
  }
});
