// SPDX-License-Identifier: MIT
// Geomorphs (node, three's BufferGeometry without a renderer): the pmzMorph attribute that
// PMZStream keeps for geomorphMaterial() holds, for every vertex added by a split while
// streaming, its parent's position and a birth time; vertices of a full upload start where
// they are. So the shader's mix(pmzMorph.xyz, position, (t - birth) / duration) starts each new
// vertex at its parent (t = birth) and ends at its own position (t = birth + duration).
// (web/test/browser.test.mjs checks the shader itself against this in Chromium.)
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { test } from 'node:test';

import { demoPmz, importPackage, importThreeLoader } from './common.mjs';

const NO_PARENT = 0xffffffff;

test('pmzMorph holds parent positions and birth times of streamed vertices', async () => {
  const { createDecoder } = await importPackage();
  const { PMZStream } = await importThreeLoader();
  const bytes = readFileSync(demoPmz());
  const s = new PMZStream(await createDecoder(), { geomorph: true });
  const births = [];
  for (let at = 0; at < bytes.length; at += 4096) {
    assert.equal(s.feed(bytes.subarray(at, at + 4096)), 'ok');
    s.update(0.5);  // a few splits per update: many generations of births
    births.push(performance.now() / 1000);
  }
  assert.equal(s.finish(), 'ok');
  while (!s.complete) s.update(5);
  const d = s.decoder, g = s.geometry;
  const nv = d.vertexCount;
  assert.equal(nv, d.info().fullVertices);
  const positions = d.positions(), parents = d.splitParents();
  const pos = g.getAttribute('position').array, morph = g.getAttribute('pmzMorph').array;
  const first = births[0] - 60, last = performance.now() / 1000;
  let born = 0, fixed = 0;
  const times = new Set();
  for (let v = 0; v < nv; ++v) {
    for (let k = 0; k < 3; ++k) assert.equal(pos[3 * v + k], positions[3 * v + k], `position of ${v}`);
    const w = morph[4 * v + 3];
    if (w === -1e6) {  // uploaded whole (the base mesh): no glide
      for (let k = 0; k < 3; ++k) assert.equal(morph[4 * v + k], positions[3 * v + k], `vertex ${v}`);
      ++fixed;
      continue;
    }
    const u = parents[v];
    assert.notEqual(u, NO_PARENT, `vertex ${v} glides but has no parent`);
    for (let k = 0; k < 3; ++k)
      assert.equal(morph[4 * v + k], positions[3 * u + k], `vertex ${v}: parent ${u}'s position`);
    // A birth time from this run (float32 seconds of performance.now()).
    assert.ok(w >= first && w <= last + 1, `vertex ${v} born at ${w}, run ${first}..${last}`);
    times.add(w);
    ++born;
  }
  assert.ok(fixed > 0 && fixed < nv / 10, `${fixed} of ${nv} vertices without a glide`);
  assert.equal(born + fixed, nv);
  assert.ok(times.size > 5, `only ${times.size} distinct birth times`);
  // The shader's blend at both ends, on the attribute values read back.
  const mix = (a, b, t) => a * (1 - t) + b * t;
  for (let v = 0; v < nv; ++v) {
    const w = morph[4 * v + 3];
    if (w === -1e6) continue;
    for (let k = 0; k < 3; ++k) {
      assert.equal(Math.fround(mix(morph[4 * v + k], pos[3 * v + k], 0)), positions[3 * parents[v] + k]);
      assert.equal(Math.fround(mix(morph[4 * v + k], pos[3 * v + k], 1)), positions[3 * v + k]);
    }
  }
  s.dispose();
});
